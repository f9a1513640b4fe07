"""The one pydantic-error formatter and the one finite check (robonix_common.errors)."""

from __future__ import annotations

import math

import pytest
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from robonix_common.errors import (
    check_finite,
    error_message,
    field_path,
    field_problems,
    format_validation_error,
    validation_lines,
)


class _Wall(BaseModel):
    model_config = ConfigDict(extra="forbid")
    thickness: float = Field(gt=0)
    height: float = Field(1.0, ge=0, le=3)


class _Scene(BaseModel):
    model_config = ConfigDict(extra="forbid")
    name: str
    walls: list[_Wall] = []

    @field_validator("name")
    @classmethod
    def _not_blank(cls, v: str) -> str:
        if not v.strip():
            raise ValueError("Must not be blank")
        return v


def _errors(data: object) -> ValidationError:
    with pytest.raises(ValidationError) as info:
        _Scene.model_validate(data)
    return info.value


def test_paths_index_lists_and_name_the_root() -> None:
    assert field_path(("service", 1, "name")) == "service[1].name"
    assert field_path(("walls", 0)) == "walls[0]"
    assert field_path(()) == "(top level)"
    assert field_path((), root="config") == "config"


def test_bounds_missing_and_unknown_keys_are_short_and_field_first() -> None:
    exc = _errors({"walls": [{"thickness": 1}, {"thickness": 0, "height": 9, "hieght": 1}]})
    assert validation_lines(exc) == [
        "name: missing required key",
        "walls[1].thickness: must be > 0",
        "walls[1].height: must be <= 3",
        "walls[1].hieght: unknown field",
    ]
    assert format_validation_error(exc, "scene.yaml: ").startswith("scene.yaml: name: missing required key; walls[1]")


def test_validator_text_loses_its_prefix_and_capital() -> None:
    exc = _errors({"name": "  "})
    assert format_validation_error(exc) == "name: must not be blank"
    exc = _errors({"name": "x", "walls": "no"})
    assert format_validation_error(exc).startswith("walls: input should be a valid list")


def test_unknown_wording_can_be_chosen_and_loc_is_kept() -> None:
    exc = _errors({"name": "x", "nmae": 1})
    assert format_validation_error(exc, unknown="unknown key (misspelt?)") == "nmae: unknown key (misspelt?)"
    assert field_problems(exc) == [(("nmae",), "unknown field")]


def test_duck_typed_on_errors_method() -> None:
    class Fake:
        def errors(self) -> list[dict]:
            return [{"loc": ("a", 2), "msg": "Assertion failed, Odd", "type": "assertion_error"},
                    {"loc": (), "type": "greater_than_equal", "ctx": {"ge": 1}, "msg": "x"}]

    assert format_validation_error(Fake()) == "a[2]: odd; (top level): must be >= 1"
    assert error_message({"type": "greater_than", "msg": "Input should be greater than 0"}) == \
        "input should be greater than 0"  # template without its ctx: pydantic's own text


def test_check_finite() -> None:
    assert check_finite(2.5) == 2.5
    for bad in (math.nan, math.inf, -math.inf):
        with pytest.raises(ValueError, match="must be a finite number"):
            check_finite(bad)
    with pytest.raises(ValueError, match="seconds"):
        check_finite(math.nan, "must be a finite number of seconds")

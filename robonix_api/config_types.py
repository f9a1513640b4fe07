"""Field types for providers' CMD_INIT config models (pydantic), so every provider validates topic and
frame names and coordinates the same way, with the same messages naming the field."""

from __future__ import annotations

from typing import Annotated

from pydantic import AfterValidator

from robonix_common.errors import check_finite


def _topic(v: str, *, allow_empty: bool) -> str:
    name = v.strip()
    if not name and allow_empty:
        return ""
    if " " in name or not name.lstrip("/"):
        raise ValueError(f"invalid topic name {v!r}")
    return name if name.startswith("/") else "/" + name


def _frame(v: str) -> str:
    name = v.strip().lstrip("/")
    if not name or " " in name:
        raise ValueError(f"invalid frame name {v!r}")
    return name


#: A ROS topic name; a leading "/" is added.
TopicName = Annotated[str, AfterValidator(lambda v: _topic(v, allow_empty=False))]
#: Like TopicName, but "" is allowed and means "not set" (e.g. resolve through the atlas instead).
OptionalTopicName = Annotated[str, AfterValidator(lambda v: _topic(v, allow_empty=True))]
#: A TF frame id; a leading "/" is dropped (tf2 convention).
FrameName = Annotated[str, AfterValidator(_frame)]
#: A float that must not be NaN or infinite (poses, coordinates).
FiniteFloat = Annotated[float, AfterValidator(check_finite)]

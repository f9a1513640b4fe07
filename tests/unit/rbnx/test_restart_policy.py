"""The restart policy's arithmetic and the deploy fields that set it (no processes)."""

from __future__ import annotations

from pathlib import Path

import pytest

from rbnx.boot.supervise import RestartPolicy, RestartTracker, exit_text
from rbnx.models import ManifestProblems, load_deploy

REPO = Path(__file__).resolve().parents[3]


@pytest.mark.parametrize(("mode", "rc", "want"), [
    ("never", -9, False), ("never", 1, False),
    ("on-failure", -9, True), ("on-failure", 3, True), ("on-failure", 0, False),
    ("always", 0, True), ("always", -15, True),
])
def test_which_exits_are_restarted(mode: str, rc: int, want: bool) -> None:
    assert RestartPolicy(mode).wants_restart(rc) is want  # type: ignore[arg-type]


def test_backoff_doubles_to_its_cap_and_gives_up_after_max_consecutive_restarts() -> None:
    t = RestartTracker(RestartPolicy("on-failure", max_restarts=5, backoff_s=0.5, backoff_max_s=3.0,
                                     reset_after_s=60.0))
    delays = []
    now = 100.0
    for _ in range(5):
        assert t.on_exit(-9, now, up_since=now - 1.0) == "restart"
        assert t.due_at is not None
        delays.append(round(t.due_at - now, 3))
        assert not t.due(now)
        assert t.due(t.due_at)
        t.started()
    assert delays == [0.5, 1.0, 2.0, 3.0, 3.0]
    assert t.on_exit(-9, now, up_since=now - 1.0) == "give-up"
    assert t.restarts == 5


def test_a_long_enough_run_clears_the_consecutive_count() -> None:
    t = RestartTracker(RestartPolicy("on-failure", max_restarts=1, backoff_s=0.5))
    assert t.on_exit(1, 10.0, up_since=9.0) == "restart"
    t.started()
    assert t.on_exit(1, 11.0, up_since=10.5) == "give-up"  # crashed again at once
    assert t.on_exit(1, 200.0, up_since=100.0) == "restart"  # but after a 100 s run it is restarted
    assert t.due_at == pytest.approx(200.5)


def test_a_clean_exit_is_not_restarted_on_failure() -> None:
    t = RestartTracker(RestartPolicy("on-failure"))
    assert t.on_exit(0, 1.0, 0.0) == "stay-down"
    assert t.due_at is None


def test_exit_text_names_the_signal() -> None:
    assert exit_text(-9) == "killed by signal 9"
    assert exit_text(2) == "exited with code 2"


def test_example_deploys_restart_on_failure() -> None:
    for name in ("sim", "minimal", "real_robot"):
        d = load_deploy(REPO / "examples" / name / "deploy.yaml", {})
        assert d.atlas_restart.mode == "on-failure"
        assert d.entries, name
        assert all(e.restart.mode == "on-failure" for e in d.entries), name


def test_bad_restart_fields_are_named(tmp_path: Path) -> None:
    f = tmp_path / "deploy.yaml"
    f.write_text(f"""manifestVersion: 1
name: x
system:
  atlas:
    restart: sometimes
service:
  - name: m
    path: {REPO / 'slam_service'}
    restart: onfail
    restart_max: -1
    restart_backoff_s: 0
""")
    with pytest.raises(ManifestProblems) as exc:
        load_deploy(f, {})
    text = "\n".join(exc.value.lines)
    assert "system.atlas.restart: input should be 'never', 'on-failure' or 'always'" in text
    assert "service[0].restart: input should be 'never', 'on-failure' or 'always'" in text
    assert "service[0].restart_max: must be >= 0" in text
    assert "service[0].restart_backoff_s: must be > 0" in text


def test_defaults_without_restart_keys_never_restart(tmp_path: Path) -> None:
    f = tmp_path / "deploy.yaml"
    f.write_text(f"manifestVersion: 1\nname: x\nservice:\n  - name: m\n    path: {REPO / 'slam_service'}\n")
    d = load_deploy(f, {})
    assert d.entries[0].restart == RestartPolicy()
    assert d.atlas_restart.mode == "never"

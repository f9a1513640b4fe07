"""No silent minutes: the planner's warm-up note is printed by rbnx boot and does not count against a
client's goal timeout."""

from __future__ import annotations

import io
from types import SimpleNamespace

from rbnx.boot.notes import NoteWatch
from rbnx.demo.goals import WARMING, warming_up

NOTE = f"{WARMING} (compiling navigation kernels, first run on this machine: ~100 s): 4 s so far"


class FakeAtlas:
    """Answers Query with whatever notes the test set (the real atlas is exercised by the boot tests)."""

    def __init__(self) -> None:
        self.details: dict[str, str] = {}

    def query(self) -> list[SimpleNamespace]:
        return [SimpleNamespace(id=k, state_detail=v) for k, v in self.details.items()]


def test_note_printed_when_it_appears_rate_limited_and_when_gone() -> None:
    out = io.StringIO()
    watch, atlas = NoteWatch(period_s=0.0, every_s=3600.0, out=out), FakeAtlas()
    atlas.details = {"nav2": NOTE, "mapping": ""}
    watch.poll(atlas, ["nav2", "mapping"])
    atlas.details["nav2"] = NOTE.replace("4 s", "6 s")
    watch.poll(atlas, ["nav2", "mapping"])  # changed, but within every_s: not printed again
    atlas.details["nav2"] = ""
    watch.poll(atlas, ["nav2", "mapping"])
    assert out.getvalue().splitlines() == [f"nav2: {NOTE}", f"nav2: {WARMING}: done"]


def test_atlas_own_details_are_not_notes() -> None:
    out = io.StringIO()
    watch, atlas = NoteWatch(period_s=0.0, out=out), FakeAtlas()
    atlas.details = {"nav2": "heartbeat lapsed > 3000ms"}
    watch.poll(atlas, ["nav2"])
    assert out.getvalue() == ""


def test_only_a_pending_goal_waiting_for_warm_up_pauses_the_timeout() -> None:
    assert warming_up("PENDING", NOTE)
    assert not warming_up("RUNNING", NOTE)
    assert not warming_up("PENDING", "waiting for the first plan")

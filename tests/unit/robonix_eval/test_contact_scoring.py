"""In-process suites score a goal reached with a contact as failed (issue 21: a contact is a failure everywhere)."""

from __future__ import annotations

from robonix_eval.pipeline import GoalResult


def result(state: str, collisions: int) -> GoalResult:
    return GoalResult(goal=(3.0, 1.0, 0.0), start=(0.0, 0.0, 0.0), state=state, detail="", time=10.0,
                      path_length=3.2, shortest_length=3.0, final_error_xy=0.05, final_error_yaw=0.02,
                      within_tolerance=True, collisions=collisions, recoveries=0)


def test_contact_fails_a_reached_goal() -> None:
    hit = result("SUCCEEDED", 1)
    assert hit.reached
    assert not hit.succeeded
    d = hit.to_dict()
    assert d["reached"] is True
    assert d["succeeded"] is False


def test_clean_success_and_plain_failure_unchanged() -> None:
    assert result("SUCCEEDED", 0).succeeded
    assert result("SUCCEEDED", 0).to_dict()["succeeded"] is True
    assert not result("FAILED", 0).succeeded
    assert not result("FAILED", 2).reached

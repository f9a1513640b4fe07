"""The one-goal journal a restarted navigation process resumes from (nav2_wrapper/journal.py)."""

from nav2_wrapper.journal import GoalJournal, JournaledGoal


def test_goal_journal_round_trip_clear_and_bad_files(tmp_path, monkeypatch):
    monkeypatch.setenv("RBNX_RUN_DIR", str(tmp_path / "run"))
    j = GoalJournal.from_env("nav2")
    assert j.path == tmp_path / "run" / "nav2-goal.json"
    assert j.pending() is None
    j.record(JournaledGoal("nav-1", 8.3, 6.8, 0.5))
    assert GoalJournal.from_env("nav2").pending() == JournaledGoal("nav-1", 8.3, 6.8, 0.5)
    j.clear()
    assert j.pending() is None
    assert not j.path.exists()
    j.path.write_text("{not json")
    assert j.pending() is None                      # unreadable: ignored, never an exception
    monkeypatch.delenv("RBNX_RUN_DIR")
    none = GoalJournal.from_env("nav2")
    none.record(JournaledGoal("nav-2", 0, 0, 0))    # outside rbnx boot: nothing written
    assert none.path is None
    assert none.pending() is None

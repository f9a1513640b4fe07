"""Issue 37 item 11: a recording whose writer was SIGKILLed has no MCAP footer; `rbnx replay` refused it
("File end magic is invalid") although its complete chunks hold readable messages. Now replay publishes
what survived, after a one-line warning that the file was truncated. The writer here is a real child
process killed with SIGKILL mid-recording (chunks it finished are on disk, the open one is lost)."""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from support.procs import wait_until

from rbnx.replay import Replayer, ReplayError
from robonix_api.dds import DdsNode, Odometry

pytestmark = pytest.mark.timeout(120)

WRITER = textwrap.dedent("""
    import sys, time
    from mcap.writer import Writer
    from rbnx.record import qos_metadata
    from rbnx.rosmsg import ros_name, schema_text
    from robonix_api.dds import Odometry, Time

    fh = open(sys.argv[1], "wb")
    w = Writer(fh, chunk_size=2048)  # small chunks: most of the run is complete chunks when the kill comes
    w.start(profile="ros2", library="abuse test")
    sid = w.register_schema(name=ros_name(Odometry), encoding="ros2msg", data=schema_text(Odometry).encode())
    ch = w.register_channel(topic="/odom", message_encoding="cdr", schema_id=sid,
                            metadata={"offered_qos_profiles": qos_metadata("reliable")})
    for i in range(200):
        o = Odometry()
        o.header.stamp, o.header.frame_id = Time.from_sec(10.0 + 0.01 * i), "odom"
        o.pose.pose.position.x = float(i)
        t = 10_000_000_000 + i * 10_000_000
        w.add_message(channel_id=ch, log_time=t, publish_time=t, data=o.serialize(), sequence=i)
    fh.flush()
    print("written", flush=True)
    time.sleep(600)  # killed here, before Writer.finish() wrote the summary and footer
""")


def _killed_recording(tmp_path: Path) -> Path:
    out = tmp_path / "killed.mcap"
    proc = subprocess.Popen([sys.executable, "-c", WRITER, str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().strip() == "written"
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(30)
    assert proc.returncode == -signal.SIGKILL
    return out


def test_replay_of_a_sigkilled_recording_publishes_what_survived(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    out = _killed_recording(tmp_path)
    got: list[float] = []
    with DdsNode(name="listener") as node:
        node.create_subscription("/odom", Odometry, lambda m: got.append(m.pose.pose.position.x), "reliable", 500)
        stats = Replayer(out, rate=50.0, clock=False, delay_s=1.5).run()
        n = stats.published.get("/odom", 0)
        wait_until(lambda: len(got) == n, 20, lambda: f"{len(got)} of {n} replayed messages received")
    assert 50 <= n < 200, stats.summary()  # the finished chunks, not the one open at the kill
    assert got == [float(i) for i in range(n)]  # in order, from the start, nothing invented
    warning = [line for line in capsys.readouterr().err.splitlines() if "truncated" in line]
    assert warning == [f"rbnx replay: warning: {out} is truncated (its recorder did not finish it); replaying "
                       f"the {n} messages that survived"], warning


def test_a_file_that_is_not_mcap_is_still_refused(tmp_path: Path) -> None:
    bad = tmp_path / "junk.mcap"
    bad.write_bytes(b"not an mcap file at all" * 10)
    with pytest.raises(ReplayError, match="cannot read"):
        Replayer(bad, delay_s=0.0).run()

"""Issue 19 acceptance against the real simulated system (`rbnx boot` of examples/sim/deploy.yaml, kitchen):

- `rbnx record` of 10 s decodes with an independent decoder (mcap-ros2-support) into LaserScan, Odometry,
  TFMessage and OccupancyGrid messages whose fields equal what this test received from the same topics;
- the dashboard (`rbnx dashboard`) in headless Debian chromium: no console error, the canvas shows the
  map (dark pixels where /map has walls, light where it is free), a click on a free cell sends a goal,
  the drawn robot moves, the status line says SUCCEEDED, deactivate/activate of mapping via its buttons
  changes the shown state; a drag sets the goal's heading and the cancel button cancels it. Screenshots
  are kept in tests/artifacts/ (dashboard.png, dashboard_navigating.png).
"""

from __future__ import annotations

import io
import math
import os
import re
import signal
import subprocess
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from support.boot import RbnxBoot, rbnx_cmd
from support.browser import chromium_path, free_port, launch
from support.procs import wait_until

from robonix_api.dds import DdsNode, LaserScan, OccupancyGrid, Odometry, TFMessage

pytestmark = [pytest.mark.integration, pytest.mark.slow, pytest.mark.timeout(600)]

REPO = Path(__file__).resolve().parents[4]
SIM_DEPLOY = REPO / "examples" / "sim" / "deploy.yaml"
ARTIFACTS = Path(os.environ.get("RBNX_TEST_ARTIFACTS", REPO / "tests" / "artifacts"))
GOAL = (5.8, 3.0)  # the kitchen's island_east waypoint, 2.9 m from the start pose


@pytest.fixture(scope="module")
def sim(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    tmp = tmp_path_factory.mktemp("live")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("RBNX_SIM_SCENE", "kitchen")
        mp.setenv("RBNX_SIM_RTF", "2")
        boot = RbnxBoot(SIM_DEPLOY, tmp)
    with boot:
        boot.wait_ready(3, 240)
        st = boot.state()
        try:
            yield {"atlas": st["atlas"], "tmp": tmp, "boot": boot}
        finally:
            boot.interrupt()
            boot.wait_all_exited()


# ---------------------------------------------------------------------- recording


def _key(topic: str, m: Any) -> tuple:
    if topic == "/tf":
        return tuple((t.header.stamp.sec, t.header.stamp.nanosec, t.child_frame_id) for t in m.transforms)
    return (m.header.stamp.sec, m.header.stamp.nanosec)


def test_recording_10s_of_the_sim_decodes_into_the_published_fields(sim: dict[str, Any]) -> None:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out = sim["tmp"] / "sim10s.mcap"
    seen: dict[str, dict[tuple, Any]] = {"/scan": {}, "/odom": {}, "/tf": {}, "/map": {}}
    lock = threading.Lock()

    def keep(topic: str) -> Any:
        def cb(m: Any) -> None:
            with lock:
                seen[topic][_key(topic, m)] = m
        return cb

    with DdsNode(name="record_test") as node:
        node.create_subscription("/scan", LaserScan, keep("/scan"), "best_effort", 100)
        node.create_subscription("/odom", Odometry, keep("/odom"), "reliable", 200)
        node.create_subscription("/tf", TFMessage, keep("/tf"), "reliable", 200)
        node.create_subscription("/map", OccupancyGrid, keep("/map"), "latched", 1)
        r = subprocess.run(rbnx_cmd() + ["record", "-o", str(out), "--duration", "10", "-q"],
                           capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
        assert r.returncode == 0, r.stdout + r.stderr
        threading.Event().wait(1.0)  # let this test's readers take the last samples the recorder saw

    decoded: dict[str, list[Any]] = {}
    with open(out, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        types = {}
        for schema, channel, _msg, m in reader.iter_decoded_messages():
            decoded.setdefault(channel.topic, []).append(m)
            types[channel.topic] = schema.name
    assert types["/scan"] == "sensor_msgs/msg/LaserScan"
    assert types["/odom"] == "nav_msgs/msg/Odometry"
    assert types["/tf"] == "tf2_msgs/msg/TFMessage"
    assert types["/map"] == "nav_msgs/msg/OccupancyGrid"
    assert len(decoded["/scan"]) >= 20
    assert len(decoded["/odom"]) >= 100
    assert len(decoded["/map"]) >= 1

    matched = {t: 0 for t in seen}
    for topic, msgs in decoded.items():
        if topic not in seen:
            continue
        for m in msgs:
            ref = seen[topic].get(_key(topic, m))
            if ref is None:
                continue
            matched[topic] += 1
            _assert_equal(topic, m, ref)
    for topic in ("/scan", "/odom", "/tf"):
        assert matched[topic] >= 0.8 * len(decoded[topic]), (topic, matched[topic], len(decoded[topic]))
    assert matched["/map"] >= 1


def _assert_equal(topic: str, m: Any, ref: Any) -> None:
    if topic == "/scan":
        assert m.header.frame_id == ref.header.frame_id
        np.testing.assert_array_equal(np.asarray(m.ranges, np.float32), ref.ranges)
        assert np.float32(m.angle_increment) == np.float32(ref.angle_increment)
        assert (np.float32(m.range_min), np.float32(m.range_max)) == (np.float32(ref.range_min),
                                                                      np.float32(ref.range_max))
    elif topic == "/odom":
        assert (m.header.frame_id, m.child_frame_id) == (ref.header.frame_id, ref.child_frame_id)
        p, q = m.pose.pose, ref.pose.pose
        assert (p.position.x, p.position.y, p.orientation.z, p.orientation.w) == (
            q.position.x, q.position.y, q.orientation.z, q.orientation.w)
        assert (m.twist.twist.linear.x, m.twist.twist.angular.z) == (ref.twist.twist.linear.x,
                                                                     ref.twist.twist.angular.z)
        np.testing.assert_array_equal(np.asarray(m.pose.covariance), ref.pose.covariance)
    elif topic == "/tf":
        for a, b in zip(m.transforms, ref.transforms, strict=True):
            assert (a.header.frame_id, a.child_frame_id) == (b.header.frame_id, b.child_frame_id)
            assert (a.transform.translation.x, a.transform.translation.y, a.transform.rotation.z,
                    a.transform.rotation.w) == (b.transform.translation.x, b.transform.translation.y,
                                                b.transform.rotation.z, b.transform.rotation.w)
    elif topic == "/map":
        assert (m.info.width, m.info.height, np.float32(m.info.resolution)) == (
            ref.info.width, ref.info.height, np.float32(ref.info.resolution))
        assert (m.info.origin.position.x, m.info.origin.position.y) == (ref.info.origin.position.x,
                                                                        ref.info.origin.position.y)
        np.testing.assert_array_equal(np.asarray(m.data, np.int8), ref.data)


# ---------------------------------------------------------------------- dashboard in a browser


@pytest.fixture(scope="module")
def dashboard(sim: dict[str, Any]) -> Iterator[str]:
    port = free_port()
    log = sim["tmp"] / "dashboard.out"
    with open(log, "w") as fh:
        proc = subprocess.Popen(rbnx_cmd() + ["--atlas", sim["atlas"], "dashboard", "--port", str(port)],
                                stdout=fh, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        wait_until(lambda: "dashboard at" in log.read_text() or proc.poll() is not None, 60, "dashboard to listen")
        assert proc.poll() is None, log.read_text()
        printed = re.search(r"dashboard at (\S+)", log.read_text())
        assert printed, log.read_text()
        assert printed.group(1).startswith(f"http://127.0.0.1:{port}/?token="), log.read_text()
        yield printed.group(1)  # the printed URL: it hands the page its access key
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            assert proc.wait(30) == 0, log.read_text()
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(10)
        assert "Traceback" not in log.read_text(), log.read_text()


def _latest_map(timeout: float = 30.0) -> OccupancyGrid:
    with DdsNode(name="dash_test_map") as node:
        m = node.wait_for_message("/map", OccupancyGrid, timeout, qos="latched")
    assert m is not None, "no /map"
    return m


def _cells(m: OccupancyGrid, pred: Any, n: int, rng: np.random.Generator) -> list[tuple[int, int]]:
    grid = np.asarray(m.data, np.int16).reshape(m.info.height, m.info.width)
    rows, cols = np.nonzero(pred(grid))
    idx = rng.choice(rows.size, size=min(n, rows.size), replace=False)
    return [(int(cols[i]), int(rows[i])) for i in idx]


@pytest.mark.skipif(chromium_path() is None, reason="Debian chromium is not installed (.ci/run installs it)")
def test_dashboard_in_headless_chromium(sim: dict[str, Any], dashboard: str) -> None:
    from PIL import Image
    from playwright.sync_api import sync_playwright

    problems: list[str] = []
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as pw:
        browser = launch(pw)
        try:
            page = browser.new_page(viewport={"width": 1320, "height": 820})
            page.on("console", lambda msg: problems.append(f"console {msg.type}: {msg.text}")
                    if msg.type in ("error", "warning") else None)
            page.on("pageerror", lambda exc: problems.append(f"page error: {exc}"))
            page.goto(dashboard)
            page.wait_for_function("window.__dash.mapVersion > 0 && window.__dash.drawnPose !== null",
                                   timeout=60_000)
            page.wait_for_selector("#state-mapping.state-active", timeout=30_000)

            # The map on the canvas: dark where /map has walls, light where it is free.
            grid_msg = _latest_map()
            info = grid_msg.info
            page.wait_for_function(  # the page shows this very map (same size and origin)
                f"(m => m && m.width === {info.width} && m.height === {info.height} && "
                f"Math.abs(m.origin_x - {info.origin.position.x}) < 1e-6 && "
                f"Math.abs(m.origin_y - {info.origin.position.y}) < 1e-6)(window.__dash.mapMeta)", timeout=30_000)
            rng = np.random.default_rng(0)
            walls = _cells(grid_msg, lambda g: g >= 65, 40, rng)
            free = _cells(grid_msg, lambda g: g == 0, 40, rng)
            shot = page.locator("#map").screenshot()
            img = np.asarray(Image.open(io.BytesIO(shot)).convert("RGB"), dtype=np.int16)
            dark = light = 0
            for cells, kind in ((walls, "wall"), (free, "free")):
                for col, row in cells:
                    cx, cy = page.evaluate(f"window.__dash.cellToCanvas({col}, {row})")
                    r, g, b = img[int(cy), int(cx)]
                    if kind == "wall":
                        dark += int(max(r, g, b) < 90 or (r > 180 and 100 < g < 170 and b < 60))  # wall or scan hit
                    else:
                        light += int(min(r, g, b) > 200 or r > 180)  # free (white) or robot/scan overlay
            assert dark >= 0.8 * len(walls), f"{dark}/{len(walls)} wall cells drawn dark"
            assert light >= 0.8 * len(free), f"{light}/{len(free)} free cells drawn light"

            # A click on a free cell sends a goal; the robot drawn on the canvas moves; SUCCEEDED.
            res, ox, oy = grid_msg.info.resolution, grid_msg.info.origin.position.x, grid_msg.info.origin.position.y
            col, row = int((GOAL[0] - ox) / res), int((GOAL[1] - oy) / res)
            grid = np.asarray(grid_msg.data, np.int16).reshape(grid_msg.info.height, grid_msg.info.width)
            assert grid[row, col] == 0, f"goal cell {GOAL} is not free in /map ({grid[row, col]})"
            start = page.evaluate("window.__dash.drawnPose")
            cx, cy = page.evaluate(f"window.__dash.worldToCanvas({GOAL[0]}, {GOAL[1]})")
            box = page.locator("#map").bounding_box()
            scale = box["width"] / page.evaluate("document.getElementById('map').width")
            page.mouse.click(box["x"] + cx * scale, box["y"] + cy * scale)
            page.wait_for_function("document.getElementById('navstatus').textContent.match(/RUNNING|ACCEPTED|SUCC/)",
                                   timeout=30_000)
            page.wait_for_function(  # on its way: keep a picture with the plan and the scan
                f"(p => p && Math.hypot(p.x - {start['x']}, p.y - {start['y']}) > 0.8)(window.__dash.drawnPose)"
                " || document.getElementById('navstatus').textContent.match(/SUCCEEDED|FAILED|CANCELED/)",
                timeout=240_000)
            page.screenshot(path=str(ARTIFACTS / "dashboard_navigating.png"))
            page.wait_for_function("document.getElementById('navstatus').textContent.match(/SUCCEEDED|FAILED|CANCELED/)",
                                   timeout=240_000)
            status = page.inner_text("#navstatus")
            assert status.startswith("SUCCEEDED"), status
            end = page.evaluate("window.__dash.drawnPose")
            assert math.hypot(end["x"] - start["x"], end["y"] - start["y"]) > 1.5, (start, end)
            assert math.hypot(end["x"] - GOAL[0], end["y"] - GOAL[1]) < 0.6, end
            goal_drawn = page.evaluate("window.__dash.drawLog.length")
            assert goal_drawn > 10
            page.screenshot(path=str(ARTIFACTS / "dashboard.png"))

            # Lifecycle buttons: deactivate mapping -> shown inactive; activate -> shown active.
            page.click("#btn-deactivate-mapping")
            page.wait_for_selector("#state-mapping.state-inactive", timeout=60_000)
            page.click("#btn-activate-mapping")
            page.wait_for_selector("#state-mapping.state-active", timeout=60_000)
            assert page.inner_text("#error") == ""

            # Drag sets the goal's heading (here: up the screen = +y = yaw pi/2); the cancel button cancels.
            sx, sy = page.evaluate("window.__dash.worldToCanvas(3.5, 1.6)")
            page.mouse.move(box["x"] + sx * scale, box["y"] + sy * scale)
            page.mouse.down()
            page.mouse.move(box["x"] + sx * scale, box["y"] + (sy - 60) * scale, steps=5)
            page.mouse.up()
            page.wait_for_function("document.getElementById('navstatus').textContent.match(/RUNNING/)",
                                   timeout=60_000)
            goal = page.evaluate("window.__dash.goal")
            assert goal["yaw"] == pytest.approx(math.pi / 2, abs=0.05), goal
            assert math.hypot(goal["x"] - 3.5, goal["y"] - 1.6) < 0.1, goal
            page.click("#cancel")
            page.wait_for_function("document.getElementById('navstatus').textContent.match(/CANCELED|SUCCEEDED|FAILED/)",
                                   timeout=60_000)
            assert page.inner_text("#navstatus").startswith("CANCELED"), page.inner_text("#navstatus")
        finally:
            browser.close()
    assert not problems, problems


# ---------------------------------------------------------------------- terminal: navigate / nav-status / cancel


def _rbnx(atlas: str, *args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    return subprocess.run(rbnx_cmd() + ["--atlas", atlas, *args], capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL)


def test_navigate_status_and_ctrl_c_cancels_from_a_terminal(sim: dict[str, Any]) -> None:
    atlas = sim["atlas"]
    r = _rbnx(atlas, "navigate", "3.5", "1.6", "--yaw", "1.57")  # back to the start pose, facing +y
    assert r.returncode == 0, r.stdout + r.stderr
    assert "SUCCEEDED" in r.stdout.splitlines()[-1], r.stdout
    st = _rbnx(atlas, "nav-status")
    assert st.returncode == 0, st.stdout + st.stderr
    assert st.stdout.startswith("SUCCEEDED"), st.stdout + st.stderr

    # Ctrl-C while running: the goal is canceled, exit 130.
    log = sim["tmp"] / "navigate.out"
    with open(log, "w") as fh:
        proc = subprocess.Popen(rbnx_cmd() + ["--atlas", atlas, "navigate", "8.3", "6.8"], stdout=fh,
                                stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        wait_until(lambda: "RUNNING" in log.read_text() or proc.poll() is not None, 60, "the goal to run")
        proc.send_signal(signal.SIGINT)
        assert proc.wait(60) == 130, log.read_text()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    assert "interrupted: cancel sent" in log.read_text(), log.read_text()
    run_id = next(ln.split("run ")[-1].strip() for ln in log.read_text().splitlines() if ": run " in ln)
    st = wait_until(lambda: (lambda r: r if "CANCELED" in r.stdout else None)(_rbnx(atlas, "nav-status", run_id)),
                    60, "the run to show CANCELED")
    assert st.returncode == 0
    again = _rbnx(atlas, "cancel", run_id)
    assert again.returncode in (0, 1), again.stdout + again.stderr
    assert again.stdout.strip(), again.stdout + again.stderr
    bad = _rbnx(atlas, "nav-status", "no-such-run")
    assert bad.returncode == 1
    assert "unknown" in bad.stderr
    assert "Traceback" not in bad.stderr

"""Drive a running deploy's ROS 2 ``navigate_to_pose`` action the way a ROS 2 client does (issue 38).

    ROS_DOMAIN_ID=<the deploy's> python bench/ros_action_client.py [--goal 7.0 1.5] [--cancel-goal 2.5 4.0]

Uses the test suite's convention-level client (tests/support/ros2_action.py: raw rq/rr samples with the
rmw_cyclonedds request header, payloads made and read by rosbags from navigation2's .action text). Sends
``--goal``, prints the feedback count and the result status; then sends ``--cancel-goal``, cancels it after
its first feedback and prints the cancel reply and the result status. Exit 1 unless SUCCEEDED then CANCELED.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
for p in (ROOT, ROOT / "tests"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

from support.ros2_action import ActionClient  # noqa: E402

from robonix_api.dds import DdsNode  # noqa: E402

NAMES = {0: "UNKNOWN", 1: "ACCEPTED", 2: "EXECUTING", 3: "CANCELING", 4: "SUCCEEDED", 5: "CANCELED", 6: "ABORTED"}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--goal", type=float, nargs=2, default=(7.0, 1.5), metavar=("X", "Y"))
    ap.add_argument("--cancel-goal", type=float, nargs=2, default=(2.5, 4.0), metavar=("X", "Y"))
    ap.add_argument("--timeout", type=float, default=300.0)
    args = ap.parse_args()
    with DdsNode(name="ros2_action_client") as node:
        c = ActionClient(node.participant)
        t0 = time.monotonic()
        while not all(c.ents[r].get_matched_subscriptions() for r in ("send_goal_rq", "get_result_rq", "cancel_rq")):
            if time.monotonic() - t0 > 30:
                print("no navigate_to_pose action server found", file=sys.stderr)
                return 1
            time.sleep(0.1)
        gid = c.uuid()
        t0 = time.monotonic()
        reply = c.wait_reply("send_goal_rr", c.send_goal(gid, *args.goal), 30)
        print(f"goal {tuple(args.goal)}: accepted={bool(reply.accepted)}")
        result = c.wait_reply("get_result_rr", c.get_result(gid), args.timeout)
        fb = [f for f in c.feedback if bytes(f.goal_id.uuid) == bytes(gid.uuid)]
        print(f"result {NAMES[result.status]} after {time.monotonic() - t0:.1f} s; {len(fb)} feedback messages, "
              f"first distance_remaining {fb[0].feedback.distance_remaining:.2f} m" if fb else "no feedback")
        ok = result.status == 4
        gid2 = c.uuid()
        print(f"goal {tuple(args.cancel_goal)}: accepted="
              f"{bool(c.wait_reply('send_goal_rr', c.send_goal(gid2, *args.cancel_goal), 30).accepted)}")
        while not any(bytes(f.goal_id.uuid) == bytes(gid2.uuid) for f in c.feedback):
            time.sleep(0.05)
            c.poll()
        cancel = c.wait_reply("cancel_rr", c.cancel(gid2), 30)
        print(f"cancel: return_code {cancel.return_code}, goals_canceling {len(cancel.goals_canceling)}")
        result2 = c.wait_reply("get_result_rr", c.get_result(gid2), 30)
        print(f"result {NAMES[result2.status]}")
        c.close()
    return 0 if ok and result2.status == 5 else 1


if __name__ == "__main__":
    sys.exit(main())

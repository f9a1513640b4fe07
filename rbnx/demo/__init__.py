"""`rbnx demo` underneath: boot the sim deploy as a child (:mod:`~rbnx.demo.boot`), pick goals
(:mod:`~rbnx.demo.goals`), send and follow them over gRPC (:mod:`~rbnx.demo.rpc`, :mod:`~rbnx.demo.goalrun`),
show progress (:mod:`~rbnx.demo.live`), record the map and the run (:mod:`~rbnx.demo.record`) and write
the report (:mod:`~rbnx.demo.report`). The command itself is :mod:`rbnx.commands.demo`.
"""

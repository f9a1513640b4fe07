"""hal_panda_mobile: the MuJoCo mobile-base primitive (holonomic chassis + 2-D lidar + scenes).

``hal_panda_mobile.sim`` is the core — numpy/dataclasses in and out, no DDS, gRPC, atlas or file format
(``hal_panda_mobile.files`` reads the robot and scene YAML into its dataclasses) — so a thin
provider can wrap it and benchmarks can step it in-process with the SLAM and navigation cores::

    from hal_panda_mobile.files import load_robot_description, load_scene
    from hal_panda_mobile.sim import PandaMobileSim
    sim = PandaMobileSim(load_robot_description(), load_scene("apartment"), seed=0)
    sim.set_cmd_vel(0.3, 0.0, 0.2)      # body-frame twist, held for cmd_vel_timeout of sim time
    sim.step(50)                        # 50 x 2 ms physics
    scan, odom, gt = sim.scan(), sim.odometry(), sim.ground_truth()

Conventions: sim time only (never wall clock); odometry's twist and ground truth's velocities are in
the body frame; by default the odom frame coincides with the world frame (so maps line up with
``ground_truth_grid``); scan ranges follow REP-117 (+inf no return/dropout, -inf closer than
range_min). Bad input raises ``SimConfigError`` (a ValueError) whose message names the field.
Not thread-safe: one thread owns the sim.
"""

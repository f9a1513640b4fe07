"""The live web dashboard: map, robot, plan, scan, goal, provider lifecycle (see ``server`` and ``state``)."""

"""In-process evaluation: the sim, SLAM and navigation cores stepped together, deterministically."""

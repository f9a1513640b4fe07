"""Unit tests, one directory per package: no processes, sockets, DDS participants or gRPC servers; fast."""

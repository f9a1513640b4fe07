"""Generated protobuf/gRPC stubs (see robonix_api.codegen)."""

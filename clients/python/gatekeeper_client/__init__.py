"""Python clients of gatekeeperd; the gRPC stubs (gatekeeper_client.v1) are generated when the package is built."""

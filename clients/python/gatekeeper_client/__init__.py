"""Python clients of gatekeeperd (stubs generated from proto/ at build time into build/python)."""

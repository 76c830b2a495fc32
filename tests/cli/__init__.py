"""Command-line edges: odd option values, port lists, repeated requests (real subprocesses)."""

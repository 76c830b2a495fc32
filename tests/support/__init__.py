"""Helpers shared by the tests (a tiny device kind, registered through DEVSIM_EXTRA_KINDS)."""

"""Benchmarks, run from a checkout with ``rld bench NAME`` (see ``rld bench --help``)."""

"""Benchmarks behind `tui-gym bench`: they print figures, never assert."""

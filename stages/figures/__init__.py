"""Figures drawn from stored stage results (matplotlib is imported inside each function)."""

"""Benchmarks: speed and memory of every stage, each compared with a baseline measured in the same run."""

"""Benchmark protocols and baselines: localization methods run on marsscene's run folders and
bags and scored against ground truth (the MarsLab paper's experiments). Above the run side and
sweeps: it calls them like any user."""

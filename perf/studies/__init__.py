"""Studies: parameter sweeps and one-off investigations behind the results pages."""

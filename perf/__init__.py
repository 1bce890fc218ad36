"""marsscene's benchmark suite: ``python perf/run.py list`` lists it (see ``perf/run.py``)."""

"""Speed and memory: wall time, peak RSS, steps or scans a second."""

"""Benchmarks of the engine, printed beside their anchors (the paper's Table 2)."""

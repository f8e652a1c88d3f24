"""The evaluation: where the tetrahedral proxy is fast, where it is
accurate, and where other methods (voxel proxy, surface god-object) break.

`hapticut evaluate --out docs/evaluation` runs all of it (evaluation.run.run_all)."""

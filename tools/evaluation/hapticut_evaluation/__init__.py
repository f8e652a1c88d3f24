"""Hapticut's evaluation (not part of the product): where the tetrahedral proxy is fast,
where it is accurate, and where other methods (voxel proxy, surface god-object) break.

`python -m hapticut_evaluation --out docs/evaluation` (or `hapticut-evaluate`) runs all
of it (run.run_all) from the repository's root."""

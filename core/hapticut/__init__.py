"""Hapticut: feel and animate a blade cutting through layered material.

The engine (``hapticut._core``, C++) implements the tetrahedral proxy method of
Tanaka, Hirota and Kaneko; this package adds scene files, scene building,
benchmarks and the ``hapticut`` command.
"""

__version__ = "0.1.0"

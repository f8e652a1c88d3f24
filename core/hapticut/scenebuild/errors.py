"""Errors of scene building."""

from __future__ import annotations


class BuildError(ValueError):
    """An input scene building cannot use; the message names the region and the problem.

    ``region`` is the region's name ("" when the problem is not one region's), ``problem``
    the rest of the message.
    """

    def __init__(self, region: str, problem: str) -> None:
        super().__init__(f"region {region!r}: {problem}" if region else problem)
        self.region = region
        self.problem = problem

    def __reduce__(self):
        return (type(self), (self.region, self.problem))


class BuildCancelled(Exception):  # noqa: N818 - a cancel is not an error
    """The progress callback asked to stop; nothing was written."""

"""Sub-commands of ``hapticut`` (see hapticut.cli)."""

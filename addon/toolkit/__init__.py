"""Reaching the installed toolkit: finding and running it, its material table, the link to
its numpy-only modules, the preferences that say where it is, and Blender units in mm."""

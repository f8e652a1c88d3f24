"""Authoring a scene: what a .blend stores, its exchange with the builder, the checks, the
build (Tetrahedralize) and its preview and report, and the work folder."""

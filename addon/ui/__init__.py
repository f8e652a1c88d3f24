"""The sidebar's panels: the scene's (regions, blades, checks, build, report) and the live
ones (session, bake)."""

"""The live session: the servo process and its link, the stream drawn in the viewport, the
devices offered, and a blade's keyframed path as the sim device's."""

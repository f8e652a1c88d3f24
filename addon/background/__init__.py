"""Work too long for one call on the main thread: steps, the job that runs them from a timer,
waiting on them from a script, and undo steps for what a timer changes."""

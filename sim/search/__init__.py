"""The searches over the evaluation: the plant fitted to the paper or to rig logs, and the controllers tuned on it."""

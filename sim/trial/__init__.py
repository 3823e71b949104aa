"""One trial: the firmware in the loop with the model (the bridge), its camera, its recording and its live view."""

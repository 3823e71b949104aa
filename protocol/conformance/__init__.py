"""Protocol conformance suite: drives a firmware over a serial device path through the whole message set."""

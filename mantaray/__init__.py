"""MANTA-RAY control stack: Python side of the protocol, host tools and simulation."""

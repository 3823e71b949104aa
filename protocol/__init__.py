"""MANTA-RAY serial protocol: generated messages, payload codec and framing (the Python side of protocol/)."""

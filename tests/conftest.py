"""Pytest configuration of the repository's tests: loads the conformance suite's plugin (--port, fixtures)."""
pytest_plugins = ["mantaray.protocol.conformance.plugin"]

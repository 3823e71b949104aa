"""Pytest configuration of the repository's tests: the conformance suite's plugin (--port, fixtures), headless GL."""
import mantaray.sim  # noqa: F401  (before any test imports mujoco: it picks EGL where there is no display)

pytest_plugins = ["mantaray.protocol.conformance.plugin"]

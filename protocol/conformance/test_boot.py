"""Conformance: boot, the message a firmware sends once as it starts, naming why it started."""

from __future__ import annotations

from mantaray.protocol import messages as m


def test_the_firmware_announces_its_start_with_boot_and_a_known_cause(session_boot):
    assert isinstance(session_boot, m.Boot)
    assert session_boot.reset_cause in {cause.value for cause in m.ResetCause}

"""Every message of protocol/schema.toml has a conformance case: a test of protocol/conformance/ that names it."""

from __future__ import annotations

import re

from mantaray.paths import REPO
from mantaray.protocol import messages as m
from mantaray.protocol.codec import Message

CONFORMANCE = REPO / "protocol" / "conformance"


def test_every_schema_message_has_a_conformance_case():
    """PROTOCOL.md, Adding a message: its last step. A message no case sends or expects is a message whose firmware
    side nothing checks on a board."""
    cases = "".join(path.read_text() for path in sorted(CONFORMANCE.glob("test_*.py")))
    messages = [
        cls for cls in vars(m).values() if isinstance(cls, type) and issubclass(cls, Message) and cls is not Message
    ]
    assert len(messages) == len({cls.ID for cls in messages}) >= 19
    missing = [cls.NAME for cls in messages if not re.search(rf"\bm\.{cls.__name__}\b", cases)]
    assert not missing, f"no conformance case names {', '.join(missing)} (protocol/conformance/test_*.py)"

"""Frame layer against known answers: CRC-16, COBS, every protocol/vectors.json vector, and generate.py --check."""

from __future__ import annotations

import binascii
import importlib.util
import json
import math
import random
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from mantaray.protocol import messages as m
from mantaray.protocol.codec import Message
from mantaray.protocol.framing import (
    Frame,
    FrameDecoder,
    FrameError,
    cobs_decode,
    cobs_encode,
    crc16,
    encode_frame,
    encode_packet,
)

REPO = Path(__file__).resolve().parent.parent
PROTOCOL = REPO / "protocol"
VECTORS = json.loads((PROTOCOL / "vectors.json").read_text())


# ------------------------------------------------------------------------------------------- CRC-16
def test_crc16_check_value():
    assert crc16(b"123456789") == 0x29B1
    check = VECTORS["crc16_check"]
    assert check["algorithm"] == "CRC-16/CCITT-FALSE"
    assert crc16(check["input_ascii"].encode()) == int(check["crc"], 16)


def test_crc16_of_nothing_is_the_init_value():
    assert crc16(b"") == 0xFFFF


@pytest.mark.parametrize("length", [1, 2, 3, 7, 44, 255, 1000])
def test_crc16_matches_binascii_crc_hqx(length):
    rng = random.Random(length)
    for _ in range(50):
        data = rng.randbytes(length)
        assert crc16(data) == binascii.crc_hqx(data, 0xFFFF)


def test_crc16_is_incremental():
    rng = random.Random(7)
    data = rng.randbytes(300)
    for cut in (0, 1, 150, 299, 300):
        assert crc16(data[cut:], crc16(data[:cut])) == crc16(data)


# --------------------------------------------------------------------------------------------- COBS
def _h(text: str) -> bytes:
    return bytes.fromhex(text.replace(" ", ""))


# The examples of the Wikipedia article "Consistent Overhead Byte Stuffing" (encoded form without the
# trailing 0x00 delimiter, which cobs_encode does not append).
WIKIPEDIA_COBS = [
    (_h("00"), _h("01 01")),
    (_h("00 00"), _h("01 01 01")),
    (_h("00 11 00"), _h("01 02 11 01")),
    (_h("11 22 00 33"), _h("03 11 22 02 33")),
    (_h("11 22 33 44"), _h("05 11 22 33 44")),
    (_h("11 00 00 00"), _h("02 11 01 01 01")),
    (bytes(range(0x01, 0xFF)), b"\xff" + bytes(range(0x01, 0xFF))),  # 01..FE
    (b"\x00" + bytes(range(0x01, 0xFF)), b"\x01\xff" + bytes(range(0x01, 0xFF))),  # 00 01..FE
    (bytes(range(0x01, 0x100)), b"\xff" + bytes(range(0x01, 0xFF)) + b"\x02\xff"),  # 01..FF
    (bytes(range(0x02, 0x100)) + b"\x00", b"\xff" + bytes(range(0x02, 0x100)) + b"\x01\x01"),  # 02..FF 00
    (bytes(range(0x03, 0x100)) + b"\x00\x01", b"\xfe" + bytes(range(0x03, 0x100)) + b"\x02\x01"),  # 03..FF 00 01
]
# Wikipedia's examples 7 and 8 end on a full 254-byte block and omit the final empty block; this encoder
# (and firmware/lib/core/cobs.cpp, which it must match) follows Cheshire & Baker's original StuffData and
# writes it as one more 0x01 code byte. Both forms decode to the same data; protocol packets are at most
# MAX_PACKET = 44 bytes, so a 254-byte block never occurs on the link.
CHESHIRE_BAKER_TAIL = {6, 7}


@pytest.mark.parametrize("index", range(len(WIKIPEDIA_COBS)))
def test_cobs_wikipedia_examples(index):
    data, encoded = WIKIPEDIA_COBS[index]
    assert cobs_decode(encoded) == data
    if index in CHESHIRE_BAKER_TAIL:
        assert cobs_encode(data) == encoded + b"\x01"
        assert cobs_decode(encoded + b"\x01") == data
    else:
        assert cobs_encode(data) == encoded


def test_cobs_round_trips_random_data():
    rng = random.Random(1234)
    for _ in range(2000):
        length = rng.choice([0, 1, 2, 5, 44, 253, 254, 255, 508, 600])
        weights = rng.choice([0.0, 0.1, 0.5, 0.9])
        data = bytes(0 if rng.random() < weights else rng.randrange(1, 256) for _ in range(length))
        encoded = cobs_encode(data)
        assert 0 not in encoded
        assert len(encoded) <= len(data) + 1 + len(data) // 254 + 1
        assert cobs_decode(encoded) == data


def test_cobs_empty_input():
    assert cobs_encode(b"") == b"\x01"
    assert cobs_decode(b"\x01") == b""


@pytest.mark.parametrize("bad", [b"\x00", b"\x03\x11", b"\x02\x00", b"\x05\x11\x22\x00\x33", b"\x02\x11\x00"])
def test_cobs_decode_rejects_malformed(bad):
    with pytest.raises(ValueError):
        cobs_decode(bad)


# ------------------------------------------------------------------------------------ vectors.json
def _kwargs(cls: type[Message], fields: dict) -> dict:
    """Vector `fields` (enum members by name, flags as ints) -> constructor arguments of cls."""
    out = {}
    for spec in cls.FIELDS:
        value = fields[spec.name]
        if spec.kind is not None:
            value = spec.kind[value.upper()] if isinstance(value, str) else spec.kind(value)
        elif spec.count > 1:
            value = tuple(value)
        out[spec.name] = value
    return out


def _assert_field_equal(spec, got, want):
    if spec.count > 1:
        assert len(got) == spec.count and len(want) == spec.count, spec.name
        for g, w in zip(got, want, strict=True):
            _assert_element_equal(spec, g, w)
    else:
        _assert_element_equal(spec, got, want)


def _assert_element_equal(spec, got, want):
    if spec.scale is not None:
        assert abs(got - want) <= spec.scale / 2, (spec.name, got, want)
    elif spec.fmt == "f":
        if isinstance(want, float) and math.isnan(want):
            assert math.isnan(got), (spec.name, got)
        else:
            assert got == want, (spec.name, got, want)  # f32 fields: exactly
    elif spec.kind is not None and isinstance(want, str):
        assert got == spec.kind[want.upper()], (spec.name, got, want)
    else:
        assert int(got) == want and type(got) is not float, (spec.name, got, want)


def _check_yield(item, want):
    if want["yield"] == "frame":
        assert isinstance(item, Frame), (item, want)
        assert item.id == want["id"]
        assert item.seq == want["seq"]
        assert item.payload == bytes.fromhex(want["payload"])
        if "message" in want:
            msg = item.message()
            assert msg.NAME == want["message"]
            assert type(msg) is m.MESSAGES[want["id"]]
            assert set(want["fields"]) == {s.name for s in msg.FIELDS}
            for spec in msg.FIELDS:
                _assert_field_equal(spec, getattr(msg, spec.name), want["fields"][spec.name])
    else:
        assert isinstance(item, FrameError) and item.kind == want["yield"], (item, want)


VECTOR_IDS = [v["name"] for v in VECTORS["vectors"]]


DECODE_VECTORS = [pytest.param(v, id=v["name"]) for v in VECTORS["vectors"]]


@pytest.mark.parametrize("vector", DECODE_VECTORS)
def test_vector_decodes_to_its_yields(vector):
    wire = bytes.fromhex(vector["wire"])
    decoder = FrameDecoder()
    out = decoder.feed(wire)
    assert len(out) == len(vector["yields"]), out
    for item, want in zip(out, vector["yields"], strict=True):
        _check_yield(item, want)
    assert decoder.crc_errors == sum(y["yield"] == "crc_error" for y in vector["yields"])
    assert decoder.frame_errors == sum(y["yield"] == "frame_error" for y in vector["yields"])


@pytest.mark.parametrize("vector", VECTORS["vectors"], ids=VECTOR_IDS)
def test_vector_decodes_byte_by_byte(vector):
    wire = bytes.fromhex(vector["wire"])
    decoder = FrameDecoder()
    out = [item for byte in wire for item in decoder.feed(bytes([byte]))]
    assert out == FrameDecoder().feed(wire)


SINGLE_FRAMES = [
    v
    for v in VECTORS["vectors"]
    if len(v["yields"]) == 1 and v["yields"][0]["yield"] == "frame" and bytes.fromhex(v["wire"]).count(0) == 1
]


def test_vectors_cover_every_message():
    named = {v["yields"][0].get("message") for v in SINGLE_FRAMES}
    assert {cls.NAME for cls in m.MESSAGES.values()} <= named


@pytest.mark.parametrize("vector", SINGLE_FRAMES, ids=[v["name"] for v in SINGLE_FRAMES])
def test_vector_fields_encode_to_its_wire(vector):
    want = vector["yields"][0]
    wire = bytes.fromhex(vector["wire"])
    assert encode_packet(want["id"], want["seq"], bytes.fromhex(want["payload"])) == wire
    if "message" in want:
        cls = m.MESSAGES[want["id"]]
        assert cls.NAME == want["message"]
        msg = cls(**_kwargs(cls, want["fields"]))
        assert msg.encode_payload() == bytes.fromhex(want["payload"])
        assert encode_frame(msg, want["seq"]) == wire


def test_vector_crc_error_is_one_bit_off_a_valid_frame():
    """The flipped-bit vector is a well-formed COBS packet one bit away from a valid one: it tests the CRC."""
    flipped = next(v for v in VECTORS["vectors"] if "flipped bit" in v["name"])
    packet = cobs_decode(bytes.fromhex(flipped["wire"])[:-1])

    def valid(p: bytes) -> bool:
        return crc16(p[:-2]) == int.from_bytes(p[-2:], "little")

    def flip(p: bytes, bit: int) -> bytes:
        q = bytearray(p)
        q[bit // 8] ^= 1 << (bit % 8)
        return bytes(q)

    assert not valid(packet)
    assert sum(valid(flip(packet, bit)) for bit in range(len(packet) * 8)) == 1


# ---------------------------------------------------------------------------------- generate.py
def test_generator_check_passes():
    result = subprocess.run(
        [sys.executable, str(PROTOCOL / "generate.py"), "--check"], capture_output=True, text=True, cwd=REPO, timeout=60
    )
    assert result.returncode == 0, result.stderr


def test_generated_tables_equal_the_schema():
    """What each message is taken in and what each controller reads: messages.py's tables are schema.toml's, and the
    host reads them (no second copy)."""
    import tomllib

    from mantaray.host import controller_settings, session

    schema = tomllib.loads((PROTOCOL / "schema.toml").read_text())
    assert m.STATE_ERROR == m.ErrorCode[schema["protocol"]["state_error"].upper()]
    for msg in schema["messages"]:
        cls = m.MESSAGES[msg["id"]]
        assert cls.STATES == {m.State[s.upper()] for s in msg.get("states", ())}, msg["name"]
    controllers = schema["controllers"]
    assert set(m.CONTROLLER_AXES) == set(m.CONTROLLER_SETTINGS) == set(m.CONTROLLER_CONFIGURE) == set(m.Controller)
    for kind in m.Controller:
        table = controllers[kind.name.lower()]
        assert m.CONTROLLER_AXES[kind] == tuple(m.Axis[a.upper()] for a in table["axes"])
        assert [cls.NAME for cls in m.CONTROLLER_SETTINGS[kind]] == table["settings"]
        assert list(m.CONTROLLER_CONFIGURE[kind]) == table["configure"]
    assert {cls.NAME for cls in m.SETTINGS_MESSAGES} == {n for c in controllers.values() for n in c["settings"]}
    assert set(m.PAPER_AXES) == {m.Axis[a.upper()] for c in controllers.values() if c["paper"] for a in c["axes"]}
    assert session.CONTROLLER_AXES is m.CONTROLLER_AXES and session.PAPER_AXES is m.PAPER_AXES
    assert list(controller_settings.SETTINGS_MESSAGES.values()) == list(m.SETTINGS_MESSAGES)


@pytest.mark.parametrize(
    "edit, needle",
    [
        (lambda s: s["messages"][1].update(states=["idle", "asleep"]), "asleep"),
        (lambda s: s["messages"][1].pop("states"), "lacks states"),
        (lambda s: s["controllers"]["cascade"].update(axes=["vx", "vz"]), "vz"),
        (lambda s: s["controllers"]["scheduled"].update(settings=["telemetry"]), "telemetry"),
        (lambda s: s["controllers"].pop("euclidean"), "one table per"),
        (lambda s: s["protocol"].update(state_error="sleepy"), "sleepy"),
    ],
)
def test_the_generator_refuses_a_state_or_controller_table_naming_the_unknown(edit, needle):
    gen = _load_generate(PROTOCOL / "generate.py")
    schema = gen.load_schema()
    edit(schema)
    with pytest.raises(gen.SchemaError, match=needle):
        gen.check_behaviour(schema)


def test_the_behaviour_tables_are_not_in_the_schema_hash():
    """states and [controllers] say nothing of the wire layout: changing them leaves the identify handshake alone."""
    gen = _load_generate(PROTOCOL / "generate.py")
    schema = gen.load_schema()
    before = gen.schema_hash(schema)
    schema["messages"][1]["states"] = ["idle", "running"]
    schema["controllers"]["manhattan"]["axes"] = ["radial"]
    assert gen.schema_hash(schema) == before


def test_the_boot_gains_are_reported_at_identify_not_hashed():
    """A retuned boot gain keeps the schema hash (no byte on the wire changes) and changes the CRC identify reports;
    a changed field of a message changes the hash."""
    gen = _load_generate(PROTOCOL / "generate.py")
    schema = gen.load_schema()
    hash_before, crc_before = gen.schema_hash(schema), gen.boot_gains_crc(schema)
    schema["pid_defaults"]["x"]["kp"] = 40.0
    assert gen.schema_hash(schema) == hash_before
    assert gen.boot_gains_crc(schema) != crc_before
    schema["messages"][1]["fields"][0]["type"] = "u16"
    assert gen.schema_hash(schema) != hash_before


def test_vectors_are_what_their_generator_writes():
    """vectors.json is written by protocol/make_vectors.py from cases stated once; a hand edit is caught."""
    result = subprocess.run(
        [sys.executable, str(PROTOCOL / "make_vectors.py"), "--check"],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr


def test_vector_generator_check_fails_on_an_edited_copy(tmp_path, monkeypatch):
    from mantaray.protocol import make_vectors

    edited = tmp_path / "vectors.json"
    edited.write_text(make_vectors.render().replace('"seq": 6', '"seq": 7', 1))
    monkeypatch.setattr(make_vectors, "VECTORS", edited)
    assert make_vectors.main(["--check"]) == 1
    assert make_vectors.main([]) == 0 and make_vectors.main(["--check"]) == 0  # rewritten: fresh again


def _load_generate(path: Path):
    spec = importlib.util.spec_from_file_location(f"_generate_{abs(hash(str(path)))}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_generator_outputs_match_and_detect_an_edit():
    gen = _load_generate(PROTOCOL / "generate.py")
    outputs = gen.outputs()
    py_text = outputs[gen.PY_OUT]
    assert gen.PY_OUT == PROTOCOL / "messages.py"
    assert py_text == gen.PY_OUT.read_text()
    edited = py_text.replace("SCHEMA_HASH = ", "SCHEMA_HASH = 1 + ", 1)
    assert edited != py_text  # what --check compares: a hand edit no longer equals the generated text
    assert f"SCHEMA_HASH = 0x{gen.schema_hash(gen.load_schema()):08X}" in py_text


def test_generator_check_fails_on_an_edited_copy(tmp_path):
    """--check, run on a copy of the tree whose messages.py was hand-edited, exits 1 and names the file."""
    gen = _load_generate(PROTOCOL / "generate.py")
    sources = ("generate.py", "generate_rig.py", "codegen.py", "rig.py", "boards.py", "schema.toml", "rig.toml")
    rigs = list((PROTOCOL / "rigs").glob("*.toml"))
    for path in [PROTOCOL / name for name in (*sources, "vectors.json")] + rigs + list(gen.outputs()):
        if not path.exists():
            continue
        target = tmp_path / path.relative_to(REPO)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(path, target)
    copy = tmp_path / "protocol" / "generate.py"
    ok = subprocess.run([sys.executable, str(copy), "--check"], capture_output=True, text=True, timeout=60)
    assert ok.returncode == 0, ok.stderr  # the untouched copy is fresh
    messages = tmp_path / "protocol" / "messages.py"
    messages.write_text(messages.read_text().replace("MAX_WIRE = 46", "MAX_WIRE = 47"))
    stale = subprocess.run([sys.executable, str(copy), "--check"], capture_output=True, text=True, timeout=60)
    assert stale.returncode == 1
    assert "messages.py" in stale.stderr
    assert (PROTOCOL / "messages.py").read_text() == gen.outputs()[gen.PY_OUT]  # the repository is untouched

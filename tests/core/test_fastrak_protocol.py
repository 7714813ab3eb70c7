"""FASTRAK protocol: records, replies, and garbage that is counted, never raised."""

import struct

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maizeviz.digitizer import protocol as fp
from maizeviz.digitizer.geometry import euler_matrix, to_reference_frame


def test_default_ascii_record():
    line = b"01   16.08  -0.38   0.71   3.05   1.12  -0.67\r\n"
    assert len(line) == 47 == fp.ascii_length(fp.DEFAULT_ITEMS)
    rec = fp.RecordParser().feed(line)[0]
    assert rec.station == 1 and rec.error == " " and rec.trustworthy
    assert rec.position == (16.08, -0.38, 0.71) and rec.angles == (3.05, 1.12, -0.67)


def test_touching_fields_and_sign_either_side():
    rec = fp.RecordParser().feed(b"02  -12.50  30.25   5.00-170.33  45.10   0.00\r\n")[0]
    assert rec.station == 2 and rec.angles[0] == -170.33
    rec = fp.RecordParser().feed(b"01 -  0.38   1.00   2.00   0.00   0.00   0.00\r\n")[0]
    assert rec.position[0] == -0.38


def test_stylus_item_and_bit_error():
    p = fp.RecordParser({1: fp.STYLUS_ITEMS})
    recs = p.feed(b"01x  16.08  -0.38   0.71   3.05   1.12  -0.67 1\r\n"
                  b"01   16.08  -0.38   0.71   3.05   1.12  -0.67 0\r\n")
    assert [r.stylus for r in recs] == [1, 0]
    assert not recs[0].trustworthy and recs[1].trustworthy


def test_extended_precision_items():
    items = (52, 54, 1)
    line = b"01 " + b"+1.2345E+01 -6.0000E-01 +7.5000E+00 " + b"+1.0000E+00 +2.0000E+00 -3.0000E+00 " + b"\r\n"
    rec = fp.RecordParser({1: items}).feed(line)[0]
    assert rec.position == pytest.approx((12.345, -0.6, 7.5))
    assert rec.angles == pytest.approx((1, 2, -3))


def test_binary_record_from_the_manual():
    raw = bytes.fromhex("3031200000803f0000004000004040000080400000a0400000c0400d0a")
    assert len(raw) == 29
    rec = fp.RecordParser(binary=True).feed(raw)[0]
    assert rec.position == (1.0, 2.0, 3.0) and rec.angles == (4.0, 5.0, 6.0)


def test_binary_record_split_across_reads():
    raw = b"01 " + struct.pack("<6f", 1, 2, 3, 4, 5, 6) + b"\r\n"
    p = fp.RecordParser(binary=True)
    assert p.feed(raw[:10]) == []
    assert p.feed(raw[10:])[0].angles == (4.0, 5.0, 6.0)


def test_status_error_and_other_replies():
    p = fp.RecordParser()
    evs = p.feed(b"21S00A  0  3.00 VERSION".ljust(53) + b"\r\n"
                 b"2 E*ERROR*O1,2,99*ERROR* EC-3*PS5*FL2*ST0\r\n"
                 b"21l1\r\n")
    st, err, reply = evs
    assert isinstance(st, fp.Status) and st.flags == 0xA
    assert st.centimetres and st.continuous and not st.binary
    assert isinstance(err, fp.ErrorReply) and err.code == -3 and err.command == "O1,2,99"
    assert isinstance(reply, fp.Reply) and reply.command == "l"


def test_garbled_and_truncated_are_counted_and_parsing_goes_on():
    good = b"01   16.08  -0.38   0.71   3.05   1.12  -0.67\r\n"
    p = fp.RecordParser()
    evs = p.feed(b"\x00\xffnoise\r\n" + b"01   16.08  -0.3\r\n" + good + b"09xyz\r\n" + good)
    kinds = [type(e).__name__ for e in evs]
    assert kinds.count("Record") == 2 and p.garbled == 3


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=400), st.booleans())
def test_random_bytes_never_raise(data, binary):
    good = b"01   16.08  -0.38   0.71   3.05   1.12  -0.67\r\n"
    p = fp.RecordParser(binary=binary)
    for k in range(0, len(data), 37):
        p.feed(data[k:k + 37])
    if not binary:
        # after garbage and a line end, the next good record is read
        evs = p.feed(b"\r\n" + good + good)
        assert any(isinstance(e, fp.Record) and e.position == (16.08, -0.38, 0.71) for e in evs)


def test_commands():
    assert fp.output_list(1, (2, 4, 16, 1)) == b"O1,2,4,16,1\r"
    assert fp.stylus_mode(1, True) == b"e1,1\r"
    assert fp.station_enable(2, False) == b"l2,0\r"
    assert fp.set_baud(115200) == b"o1152,N,8,0\r"


def test_reference_frame_round_trip():
    rng = np.random.default_rng(0)
    for _ in range(20):
        q = rng.normal(size=3) * 50
        ref = rng.normal(size=3) * 30
        ang = rng.uniform(-180, 180, 3)
        world = ref + euler_matrix(*ang) @ q
        assert to_reference_frame(world, ref, ang) == pytest.approx(q, abs=1e-9)
    r = euler_matrix(90, 0, 0)
    assert r @ [1, 0, 0] == pytest.approx([0, 1, 0])

"""E2E (Profile 1 style) in hstpf_tools.e2e: known vectors and receiver rules."""
import pytest

from hstpf_tools import e2e


@pytest.mark.parametrize("data,crc", [
    # Crc_CalculateCRC8 (SAE J1850, init 0xFF, final XOR 0xFF) vectors of the
    # AUTOSAR CRC library specification, and the catalogue check value.
    ("00000000", 0x59), ("F20183", 0x37), ("0FAA0055", 0x79), ("00FF5511", 0xB8),
    ("332255AABBCCDDEEFF", 0xCB), ("926B55", 0x8C), ("FFFFFFFF", 0x74),
    ("313233343536373839", 0x4B),
])
def test_crc8_sae_j1850_vectors(data, crc):
    assert e2e.crc8(bytes.fromhex(data), 0xFF) ^ 0xFF == crc


def _bitwise_crc8(data: bytes) -> int:
    """Independent reference: MSB-first long division by x^8+x^4+x^3+x^2+1."""
    reg = 0
    for byte in data:
        for i in range(7, -1, -1):
            top = (reg >> 7) & 1
            reg = ((reg << 1) & 0xFF) | 0
            if top ^ ((byte >> i) & 1):
                reg ^= 0x1D
    return reg


@pytest.mark.parametrize("data_id,frame,crc", [
    # Cross-checked once against an independent Profile 1 implementation
    # (PyPI autosar-e2e 1.0.0, e2e.p01.e2e_p01_protect, DATAID_BOTH).
    (0x1101, "0000123456789ABC", 0x72),
    (0x1101, "0010A08601000000", 0x4D),
    (0x0000, "0000000000000000", 0x00),
    (0x2101, "0005000000000000", 0x21),
])
def test_profile1_vectors(data_id, frame, crc):
    f = bytes.fromhex(frame)
    assert e2e.frame_crc(data_id, f) == crc
    # by hand: CRC over ID low, ID high, bytes 1..7 with init 0, no XOR
    assert _bitwise_crc8(bytes([data_id & 0xFF, data_id >> 8]) + f[1:]) == crc
    assert e2e.protect(data_id, f, f[1] & 0x0F)[0] == crc


def test_sender_counter_cycle():
    s = e2e.Sender(0x1101)
    counters = [s.protect(bytes([0, 0xA0, 1, 2, 3, 4, 5, 6]))[1] for _ in range(32)]
    assert [c & 0x0F for c in counters] == [k % 15 for k in range(32)]  # 15 never sent
    assert all(c & 0xF0 == 0xA0 for c in counters)


def _frame(counter, did=0x1101):
    f = bytearray([0, counter, 0x42, 0, 0, 0, 0, 0])  # raw counter, 15 allowed here
    f[0] = e2e.frame_crc(did, f)
    return bytes(f)


def test_receiver_rules_match_the_c_tests():
    # the same sequence as test_rx_faults_counted in tests/codec/test_e2e.c
    r = e2e.Receiver(0x1101)
    seq = [(_frame(0), 0.0, e2e.OK_INITIAL), (_frame(0), 0.1, e2e.REPEATED), (_frame(1)[:7], 0.1, e2e.WRONG_LENGTH)]
    bad = bytearray(_frame(1))
    bad[5] ^= 4
    seq += [(bytes(bad), 0.1, e2e.BAD_CRC), (_frame(1, did=0x1102), 0.1, e2e.BAD_CRC),
            (_frame(1), 0.1, e2e.OK), (_frame(3), 0.2, e2e.OK_LOST), (_frame(6), 0.3, e2e.OK_LOST),
            (_frame(10), 0.4, e2e.COUNTER_JUMP), (_frame(11), 0.45, e2e.OK), (_frame(9), 0.46, e2e.COUNTER_JUMP),
            (_frame(15), 0.47, e2e.COUNTER_JUMP), (_frame(10), 0.48, e2e.OK)]
    for f, t, want in seq:
        assert r.check(f, t) == want
    assert r.counts == {"ok": 6, "lost": 3, "wrong_length": 1, "bad_crc": 2, "repeated": 1, "jump": 3, "stale": 0}


def test_receiver_stale_once_per_episode():
    r = e2e.Receiver(0x1101, timeout_s=0.5)
    assert r.poll(10.0) == e2e.NO_DATA
    assert r.poll(10.5) == e2e.NO_DATA
    assert r.poll(10.501) == e2e.STALE
    assert r.poll(12.0) == e2e.STALE
    assert r.counts["stale"] == 1
    assert r.check(_frame(4), 12.1) == e2e.OK_INITIAL
    assert r.check(_frame(12), 13.0) == e2e.OK_INITIAL  # gap noticed by the frame itself
    assert r.counts["stale"] == 2 and r.counts["jump"] == 0

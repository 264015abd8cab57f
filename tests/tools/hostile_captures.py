#!/usr/bin/env python3
"""Hostile capture files for the CLI, built from a good classic pcap (little-endian, microseconds).

hostile_captures.py BASE.pcap OUT_DIR   writes OUT_DIR/<case> for every case below; the table in
tests/integration/damaged_captures.sh says what ncservo must do with each.
"""
import os
import struct
import sys

FRAMES_BEFORE_DAMAGE = 100  # good records before the damage in the cases that have some


def read_pcap(path):
    data = open(path, "rb").read()
    assert data[:4] == b"\xd4\xc3\xb2\xa1", "base capture must be little-endian microsecond pcap"
    header, records, at = data[:24], [], 24
    while at + 16 <= len(data):
        sec, usec, caplen, length = struct.unpack("<IIII", data[at:at + 16])
        records.append((sec, usec, data[at + 16:at + 16 + caplen], length))
        at += 16 + caplen
    return header, records


def pcap_header(snaplen=65535, dlt=1):
    return struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, snaplen, dlt)


def pcap_record(sec, usec, frame, caplen=None, length=None):
    caplen = len(frame) if caplen is None else caplen
    length = len(frame) if length is None else length
    return struct.pack("<IIII", sec, usec, caplen, length) + frame


def pcap(records, **header):
    return pcap_header(**header) + b"".join(pcap_record(s, u, f, length=n) for s, u, f, n in records)


def block(btype, body):
    body += b"\0" * (-len(body) % 4)
    return struct.pack("<II", btype, len(body) + 12) + body + struct.pack("<I", len(body) + 12)


def shb():
    return block(0x0A0D0D0A, struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1))


def idb(dlt, snaplen=65535):
    return block(1, struct.pack("<HHI", dlt, 0, snaplen))


def epb(sec, usec, frame, interface=0, length=None):
    ts = sec * 1000000 + usec
    length = len(frame) if length is None else length
    return block(6, struct.pack("<IIIII", interface, ts >> 32, ts & 0xFFFFFFFF, len(frame), length) + frame)


def sll(frame):
    # Linux cooked header (DLT 113) for an Ethernet frame: the EtherType after the MAC addresses.
    return struct.pack(">HHH8sH", 0, 1, 6, frame[6:12] + b"\0\0", struct.unpack(">H", frame[12:14])[0]) + frame[14:]


def main():
    base, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    header, records = read_pcap(base)
    good = records[:FRAMES_BEFORE_DAMAGE]
    good_pcap = pcap(good)
    sec0, usec0, frame0, _ = records[0]
    cases = {
        "empty": b"",
        "truncated-global-header": good_pcap[:13],
        "truncated-record-header": good_pcap + pcap_record(*records[FRAMES_BEFORE_DAMAGE][:3])[:9],
        "truncated-record-data": good_pcap + pcap_record(*records[FRAMES_BEFORE_DAMAGE][:3])[:40],
        # A record longer than the file's snap length (64), then one longer than what follows it.
        "caplen-above-snaplen": pcap_header(snaplen=64) + b"".join(
            pcap_record(s, u, f) for s, u, f, _ in good),
        "caplen-above-record": good_pcap + pcap_record(sec0, usec0, frame0, caplen=len(frame0) + 5000),
        "caplen-above-original": pcap([(s, u, f, len(f) // 2) for s, u, f, _ in good]),
        "absurd-caplen": good_pcap + pcap_record(sec0, usec0, frame0, caplen=0xFFFFFFF0),
        "absurd-snaplen": pcap(good, snaplen=0xFFFFFFFF),
        "zero-length-frames": pcap_header() + b"".join(
            pcap_record(s, u, f) + pcap_record(s, u, b"") for s, u, f, _ in good),
        "timestamps-backwards": pcap([(s - (i % 7 == 3) * 5, u, f, n) for i, (s, u, f, n) in enumerate(records)]),
        "timestamp-after-2262": shb() + idb(1) + b"".join(
            epb(s + 10**10, u, f) for s, u, f, _ in good),
        "pcapng-unknown-blocks": shb() + idb(1) + b"".join(
            block(0x00000BAD, b"unknown" * (i % 5)) + epb(s, u, f) + block(0x40000BAD, b"")
            for i, (s, u, f, _) in enumerate(good)),
        "pcapng-oversized-block": shb() + idb(1) + b"".join(epb(s, u, f) for s, u, f, _ in good)
        + struct.pack("<II", 6, 0x7FFFFFF0) + b"\0" * 64,
        "pcapng-short-block": shb() + idb(1) + b"".join(epb(s, u, f) for s, u, f, _ in good)
        + struct.pack("<III", 6, 8, 8),
        "pcapng-mixed-link-types": shb() + idb(1) + b"".join(epb(s, u, f) for s, u, f, _ in good)
        + idb(113) + b"".join(epb(s, u, sll(f), interface=1) for s, u, f, _ in good),
        "pcapng-interface-out-of-range": shb() + idb(1) + b"".join(
            epb(s, u, f, interface=7 if i == 50 else 0) for i, (s, u, f, _) in enumerate(good)),
    }
    for name, content in cases.items():
        with open(os.path.join(out, name), "wb") as f:
            f.write(content)
    # A huge sparse file: the good capture, then a hole of 1 GiB that reads as zeros (zero-length
    # records with zero timestamps).
    with open(os.path.join(out, "huge-sparse"), "wb") as f:
        f.write(good_pcap)
        f.truncate(len(good_pcap) + (1 << 30))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Seed corpora for the fuzz targets, cut from real captures.

make_seeds.py OUT_DIR CAPTURE...  writes
  OUT_DIR/frame/     single packets, an option byte first (fuzz_common.hpp)
  OUT_DIR/sequence/  runs of consecutive packets in fuzz_sequence's record format
  OUT_DIR/capture/   the start of each capture file, cut at a record boundary
Reads pcap and pcapng (Ethernet, Linux SLL, SLL2); other link types are skipped.
"""
import hashlib
import os
import struct
import sys

LINK_OPTION = {1: 0, 113: 1, 276: 2}  # DLT -> fuzz_common.hpp's link bits
FRAMES_PER_CAPTURE = 80
SEQUENCE_LENGTH = 48
SEQUENCES_PER_CAPTURE = 6
CAPTURE_SEED_BYTES = 16 * 1024


def read_pcap(data):
    magic = data[:4]
    if magic in (b"\xd4\xc3\xb2\xa1", b"\x4d\x3c\xb2\xa1"):
        e = "<"
    elif magic in (b"\xa1\xb2\xc3\xd4", b"\xa1\xb2\x3c\x4d"):
        e = ">"
    else:
        return None, []
    nano = magic in (b"\x4d\x3c\xb2\xa1", b"\xa1\xb2\x3c\x4d")
    dlt = struct.unpack(e + "I", data[20:24])[0] & 0xFFFF
    packets, bounds, at = [], [], 24
    while at + 16 <= len(data):
        sec, frac, caplen, _ = struct.unpack(e + "IIII", data[at:at + 16])
        if at + 16 + caplen > len(data):
            break
        packets.append((dlt, sec * 10**9 + (frac if nano else frac * 1000), data[at + 16:at + 16 + caplen]))
        at += 16 + caplen
        bounds.append(at)
    return bounds, packets


def read_pcapng(data):
    if data[:4] != b"\x0a\x0d\x0d\x0a":
        return None, []
    e = "<" if data[8:12] == b"\x4d\x3c\x2b\x1a" else ">"
    links, resolution, packets, bounds, at = [], [], [], [], 0
    while at + 12 <= len(data):
        btype, blen = struct.unpack(e + "II", data[at:at + 8])
        if blen < 12 or at + blen > len(data):
            break
        body = data[at + 8:at + blen - 4]
        if btype == 0x0A0D0D0A:
            links, resolution = [], []
        elif btype == 1:
            links.append(struct.unpack(e + "H", body[:2])[0])
            resolution.append(10**3)  # microseconds unless if_tsresol says otherwise
            opt = 8
            while opt + 4 <= len(body):
                code, olen = struct.unpack(e + "HH", body[opt:opt + 4])
                if code == 0:
                    break
                if code == 9 and olen == 1 and body[opt + 4] < 128:
                    resolution[-1] = 10**9 // 10**body[opt + 4] if body[opt + 4] <= 9 else 1
                opt += 4 + (olen + 3) // 4 * 4
        elif btype == 6 and len(body) >= 20:
            iface, hi, lo, caplen, _ = struct.unpack(e + "IIIII", body[:20])
            if iface < len(links):
                packets.append((links[iface], ((hi << 32) | lo) * resolution[iface], body[20:20 + caplen]))
        at += blen
        bounds.append(at)
    return bounds, packets


def spread(items, count):
    if len(items) <= count:
        return list(items)
    return [items[i * len(items) // count] for i in range(count)]


def write(directory, content):
    os.makedirs(directory, exist_ok=True)
    with open(os.path.join(directory, hashlib.sha1(content).hexdigest()), "wb") as f:
        f.write(content)


def main():
    out, captures = sys.argv[1], sys.argv[2:]
    for path in captures:
        data = open(path, "rb").read()
        bounds, packets = read_pcap(data)
        if bounds is None:
            bounds, packets = read_pcapng(data)
        if bounds is None:
            print(f"make_seeds.py: {path}: not pcap or pcapng, skipped", file=sys.stderr)
            continue
        cut = max([b for b in bounds if b <= CAPTURE_SEED_BYTES] or [min(len(data), CAPTURE_SEED_BYTES)])
        write(os.path.join(out, "capture"), data[:cut])
        packets = [p for p in packets if p[0] in LINK_OPTION]
        # The start-up and then the cyclic traffic, evenly.
        for dlt, _, frame in packets[:20] + spread(packets[20:], FRAMES_PER_CAPTURE - 20):
            write(os.path.join(out, "frame"), bytes([LINK_OPTION[dlt]]) + frame)
        starts = spread(range(max(1, len(packets) - SEQUENCE_LENGTH)), SEQUENCES_PER_CAPTURE)
        for start in starts:
            run = packets[start:start + SEQUENCE_LENGTH]
            if not run:
                continue
            seed, previous = bytearray([LINK_OPTION[run[0][0]]]), run[0][1]
            for dlt, time_ns, frame in run:
                if dlt != run[0][0]:
                    continue
                step = (time_ns - previous) // 10000
                step = 0xFFFF if step < 0 else min(step, 0xFFFE)
                previous = time_ns
                seed += struct.pack("<HH", min(len(frame), 0xFFFF), step) + frame
            write(os.path.join(out, "sequence"), bytes(seed))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""A capture whose cyclic LRW carries only zeros: no layout can be inferred from it.

Usage: zero_lrw_capture.py OUTPUT CYCLES [LENGTH]. Each cycle is a master copy (WKC 0) and its
returned copy (WKC 3, source MAC with the locally administered bit set) of one LRW at logical
address 0x00010000, 1 ms apart, in a pcap file.
"""
import struct
import sys


def frame(length, wkc, returned):
    dst = b"\xff" * 6
    src = (b"\x02" if returned else b"\x00") + b"\x01\x02\x03\x04\x05"
    datagram = struct.pack("<BBIHH", 0x0C, 0, 0x00010000, length, 0) + bytes(length)
    datagram += struct.pack("<H", wkc)
    header = struct.pack("<H", len(datagram) | 0x1000)
    return dst + src + b"\x88\xa4" + header + datagram


def main():
    out, cycles = sys.argv[1], int(sys.argv[2])
    length = int(sys.argv[3]) if len(sys.argv) > 3 else 200
    with open(out, "wb") as f:
        f.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1))
        for k in range(cycles):
            for returned in (False, True):
                data = frame(length, 3 if returned else 0, returned)
                us = k * 1000 + (20 if returned else 0)
                f.write(struct.pack("<IIII", us // 1_000_000, us % 1_000_000, len(data), len(data)))
                f.write(data)


if __name__ == "__main__":
    main()

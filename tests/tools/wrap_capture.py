#!/usr/bin/env python3
"""Rewrites an Ethernet pcap frame by frame, for tests of how captures come (docs/protocol.md §8):

  --esl before|after   each frame behind or followed by a 16-byte ESL probe header whose timestamp
                       is the frame's original time (exact, ns), while the capture's own timestamps
                       get --noise-us of deterministic noise, as a PC's would
  --link sll|sll2      the frames as Linux cooked captures v1 (DLT 113) or v2 (DLT 276)

With --esl: --crc-error N,... sets the CRC-error flag on those frames (1-based), --unstamped N,...
gives those frames a header without a valid timestamp, --port P the probe port (0..11).
Reads classic pcap (microsecond or nanosecond); writes classic pcap with nanosecond timestamps.
"""
import argparse
import random
import struct
import sys

ESL_PORT_BITS = [0x0080, 0x0040, 0x0020, 0x0010, 0x0008, 0x0004, 0x0002, 0x0001,
                 0x8000, 0x4000, 0x0400, 0x0200]
ESL_CRC_ERROR = 0x1000
ESL_TIMESTAMP_VALID = 0x2000
DLT = {"eth": 1, "sll": 113, "sll2": 276}


def read_pcap(path):
    with open(path, "rb") as f:
        data = f.read()
    magic = data[:4]
    if magic in (b"\xd4\xc3\xb2\xa1", b"\x4d\x3c\xb2\xa1"):
        endian = "<"
    elif magic in (b"\xa1\xb2\xc3\xd4", b"\xa1\xb2\x3c\x4d"):
        endian = ">"
    else:
        sys.exit(f"wrap_capture: {path}: not a classic pcap")
    nano = magic in (b"\x4d\x3c\xb2\xa1", b"\xa1\xb2\x3c\x4d")
    linktype = struct.unpack(endian + "I", data[20:24])[0]
    if linktype != 1:
        sys.exit(f"wrap_capture: {path}: link type {linktype}, expected Ethernet (1)")
    pos = 24
    while pos + 16 <= len(data):
        sec, frac, incl, orig = struct.unpack(endian + "IIII", data[pos:pos + 16])
        pos += 16
        yield sec * 1_000_000_000 + (frac if nano else frac * 1000), data[pos:pos + incl], orig
        pos += incl


def esl_header(flags, timestamp_ns):
    return bytes([0x01, 0x01, 0x05, 0x10, 0x00, 0x00]) + struct.pack("<HQ", flags, timestamp_ns)


def cooked(link, frame):
    """The Ethernet frame as a Linux cooked capture: header, then the payload after the MACs."""
    source, ethertype, payload = frame[6:12], frame[12:14], frame[14:]
    if link == "sll":  # packet type 4 (sent by us), ARPHRD_ETHER, address length 6
        return struct.pack(">HHH", 4, 1, 6) + source + b"\0\0" + ethertype + payload
    # SLL2: protocol, reserved, interface index, ARPHRD_ETHER, packet type, address length
    return ethertype + b"\0\0" + struct.pack(">IHBB", 1, 1, 4, 6) + source + b"\0\0" + payload


def frames_list(text):
    return {int(n) for n in text.split(",") if n} if text else set()


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("input")
    p.add_argument("output")
    p.add_argument("--esl", choices=("before", "after"))
    p.add_argument("--link", choices=("sll", "sll2"))
    p.add_argument("--noise-us", type=float, default=300.0)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--port", type=int, default=0, choices=range(12))
    p.add_argument("--crc-error", default="")
    p.add_argument("--unstamped", default="")
    args = p.parse_args()
    if bool(args.esl) == bool(args.link):
        sys.exit("wrap_capture: give one of --esl and --link")
    rng = random.Random(args.seed)
    crc, unstamped = frames_list(args.crc_error), frames_list(args.unstamped)
    out = open(args.output, "wb")
    out.write(struct.pack("<IHHiIII", 0xA1B23C4D, 2, 4, 0, 0, 262144, DLT[args.link or "eth"]))
    last_capture = 0
    for number, (time_ns, frame, orig) in enumerate(read_pcap(args.input), start=1):
        capture_ns = time_ns
        if args.esl:
            flags = ESL_PORT_BITS[args.port]
            flags |= 0 if number in unstamped else ESL_TIMESTAMP_VALID
            flags |= ESL_CRC_ERROR if number in crc else 0
            header = esl_header(flags, time_ns)
            frame = header + frame if args.esl == "before" else frame + header
            orig += len(header)
            # the PC stamps late, by up to the noise, and never goes back
            capture_ns = max(last_capture + 1000, time_ns + int(rng.uniform(0, args.noise_us) * 1000))
        else:
            orig -= len(frame) - len(cooked(args.link, frame))
            frame = cooked(args.link, frame)
        last_capture = capture_ns
        out.write(struct.pack("<IIII", capture_ns // 1_000_000_000, capture_ns % 1_000_000_000,
                              len(frame), orig))
        out.write(frame)
    out.close()


if __name__ == "__main__":
    main()

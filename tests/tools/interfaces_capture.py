#!/usr/bin/env python3
"""Rewrite a one-interface Ethernet pcap as a pcapng of two interfaces (docs/cli.md#interfaces).

Written from the pcap and pcapng formats (pcap-savefile(5), draft-ietf-opsawg-pcapng) and the
EtherCAT frame layout of docs/protocol.md §8 alone, with the standard library only: an
independent source for what ncservo must make of such captures.

    interfaces_capture.py office IN OUT MAP
        `dumpcap -i eth0 -i any`: interface 0 is Ethernet (microseconds) with every record of IN;
        interface 1 is Linux cooked (SLL, nanoseconds, an if_tsoffset of whole seconds) with a
        UDP datagram or an ARP request after every 4th record of IN, halfway to the next by time.
    interfaces_capture.py tap IN OUT MAP
        a TAP's two directions on two ports, both Ethernet: the master copies (every working
        counter 0) on interface 0 (microseconds), the returned copies on interface 1
        (nanoseconds, an if_tsoffset); as dumpcap's threads hand two ports' records over, some
        come late: every 7th cycle's returned copy is written before its master copy, and every
        101st cycle the returned copies of three cycles come before their three master copies.

MAP (JSON): {"frames": the frame number in OUT of each record of IN, in IN's order,
"interfaces": [records of interface 0, records of interface 1]}.
"""
import json
import struct
import sys

ETHERTYPE_ETHERCAT = 0x88A4
VLAN_TAGS = (0x8100, 0x88A8)


def read_pcap(path):
    """[(time_ns, bytes)] of a pcap of Ethernet records, either byte order, micro- or nanoseconds."""
    data = open(path, "rb").read()
    for order in "<>":
        magic = struct.unpack(order + "I", data[:4])[0]
        if magic in (0xA1B2C3D4, 0xA1B23C4D):
            break
    else:
        sys.exit(f"{path}: not a pcap")
    scale = 1 if magic == 0xA1B23C4D else 1000
    link = struct.unpack(order + "I", data[20:24])[0] & 0xFFFF
    if link != 1:
        sys.exit(f"{path}: link type {link}, not Ethernet")
    records, at = [], 24
    while at + 16 <= len(data):
        seconds, fraction, captured, _ = struct.unpack(order + "IIII", data[at:at + 16])
        records.append((seconds * 1_000_000_000 + fraction * scale, data[at + 16:at + 16 + captured]))
        at += 16 + captured
    return records


def working_counters(frame):
    """The working counters of an EtherCAT frame's datagrams; None when it is no EtherCAT frame."""
    at = 12
    while at + 2 <= len(frame) and struct.unpack(">H", frame[at:at + 2])[0] in VLAN_TAGS:
        at += 4
    if at + 4 > len(frame) or struct.unpack(">H", frame[at:at + 2])[0] != ETHERTYPE_ETHERCAT:
        return None
    at += 4  # the EtherType, the EtherCAT frame header
    counters = []
    while at + 10 <= len(frame):
        length_word = struct.unpack("<H", frame[at + 6:at + 8])[0]
        length = length_word & 0x07FF
        end = at + 10 + length
        if end + 2 > len(frame):
            break
        counters.append(struct.unpack("<H", frame[end:end + 2])[0])
        at = end + 2
        if not length_word & 0x8000:
            break
    return counters


def block(kind, body):
    body += b"\0" * (-len(body) % 4)
    return struct.pack("<II", kind, 12 + len(body)) + body + struct.pack("<I", 12 + len(body))


def section():
    return block(0x0A0D0D0A, struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1))


class Interface:
    """An interface description and the timestamps of its records at its resolution and offset."""

    def __init__(self, link_type, digits, offset_s=0):
        self.link_type, self.digits, self.offset_s = link_type, digits, offset_s

    def description(self):
        options = struct.pack("<HHB3x", 9, 1, self.digits)  # if_tsresol
        if self.offset_s:
            options += struct.pack("<HHq", 14, 8, self.offset_s)  # if_tsoffset
        options += struct.pack("<HH", 0, 0)
        return block(1, struct.pack("<HHI", self.link_type, 0, 65535) + options)

    def ticks(self, time_ns):
        since = time_ns - self.offset_s * 1_000_000_000
        assert since >= 0 and since % 10 ** (9 - self.digits) == 0, "time not representable"
        return since // 10 ** (9 - self.digits)


def packet(interface_id, interface, time_ns, data):
    ticks = interface.ticks(time_ns)
    head = struct.pack("<IIIII", interface_id, ticks >> 32, ticks & 0xFFFFFFFF, len(data), len(data))
    return block(6, head + data)


def cooked(protocol, payload, outgoing):
    """A Linux cooked (SLL) header: packet type, ARPHRD_ETHER, the address, the protocol."""
    address = bytes([0x02, 0x00, 0x5E, 0x10, 0x00, 0x01, 0, 0])
    return struct.pack(">HHH8sH", 4 if outgoing else 0, 1, 6, address, protocol) + payload


def office_frame(n):
    """The n-th record of the office port: an mDNS query in UDP (not EtherCAT's port 34980), or an
    ARP request, alternately."""
    if n % 2 == 0:
        udp = struct.pack(">HHHH", 5353, 5353, 8 + 12, 0) + bytes(12)
        ip = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), n & 0xFFFF, 0, 64, 17, 0,
                         bytes([192, 168, 1, 20]), bytes([224, 0, 0, 251]))
        return cooked(0x0800, ip + udp, True)
    arp = struct.pack(">HHBBH6s4s6s4s", 1, 0x0800, 6, 4, 1, bytes(6), bytes([192, 168, 1, 20]),
                      bytes(6), bytes([192, 168, 1, n % 250 + 1]))
    return cooked(0x0806, arp, n % 4 == 1)


def office(records):
    """[(interface, time_ns, bytes, index in IN or None)] in the order written."""
    out = []
    for i, (time_ns, data) in enumerate(records):
        out.append((0, time_ns, data, i))
        if i % 4 == 3:
            following = records[i + 1][0] if i + 1 < len(records) else time_ns + 2000
            between = time_ns + max(following - time_ns, 0) // 2
            out.append((1, between, office_frame(i // 4), None))
    return out


def tap(records):
    """Each cycle's master copy on interface 0 and returned copy on interface 1, some written late
    (the module's docstring)."""
    units = []  # [[(interface, time_ns, bytes, index)], ...]: a cycle's two copies, or one record
    i = 0
    while i < len(records):
        time_ns, data = records[i]
        counters = working_counters(data)
        returned = counters is not None and any(counters)
        if not returned and i + 1 < len(records):
            next_ns, next_data = records[i + 1]
            next_counters = working_counters(next_data)
            if next_counters and any(next_counters) and next_ns > time_ns:
                units.append([(0, time_ns, data, i), (1, next_ns, next_data, i + 1)])
                i += 2
                continue
        units.append([(1 if returned else 0, time_ns, data, i)])
        i += 1
    out, k = [], 0
    while k < len(units):
        burst = units[k:k + 3]
        if k % 101 == 50 and len(burst) == 3 and all(len(u) == 2 for u in burst):
            out += [u[1] for u in burst] + [u[0] for u in burst]
            k += 3
            continue
        unit = units[k]
        out += [unit[1], unit[0]] if len(unit) == 2 and k % 7 == 3 else unit
        k += 1
    return out


def main():
    if len(sys.argv) != 5 or sys.argv[1] not in ("office", "tap"):
        sys.exit(__doc__)
    mode, source, target, map_path = sys.argv[1:]
    records = read_pcap(source)
    if not records:
        sys.exit(f"{source}: no records")
    offset_s = min(t for t, _ in records) // 1_000_000_000
    interfaces = [Interface(1, 6), Interface(113 if mode == "office" else 1, 9, offset_s)]
    written = office(records) if mode == "office" else tap(records)
    frames = [0] * len(records)
    counts = [0, 0]
    blocks = [section()] + [i.description() for i in interfaces]
    for number, (interface_id, time_ns, data, index) in enumerate(written, start=1):
        blocks.append(packet(interface_id, interfaces[interface_id], time_ns, data))
        counts[interface_id] += 1
        if index is not None:
            frames[index] = number
    open(target, "wb").write(b"".join(blocks))
    json.dump({"frames": frames, "interfaces": counts}, open(map_path, "w"))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""What tshark's stock EtherCAT dissector shows of a capture's start-up, per slave: the last FMMU
(0x0600 + 16n) and sync manager (0x0800 + 8n) values written to it by FPWR, from the dissector's own
fields (ecat.fmmu.*, ecat.syncman.*). Prints one line per station in the form of
`ncservo decode --layout`'s slave lines, so the two can be compared.

Usage: stock_layout.py TSHARK_JSON   (the output of tshark -T json --no-duplicate-keys)"""
import json
import sys


def as_list(value):
    return value if isinstance(value, list) else [value]


def num(text):
    return int(text, 0)


def datagrams(layers):
    ecat = layers.get("ecat")
    if ecat is None:
        return []
    out = []
    for ecat_layer in as_list(ecat):
        for key, value in ecat_layer.items():
            if key.startswith("EtherCAT datagram"):
                out.extend(as_list(value))
    return out


def main():
    packets = json.load(open(sys.argv[1]))
    slaves = {}  # station -> {"fmmu": {n: (...)}, "sm": {n: (...)}}
    for packet in packets:
        for dg in datagrams(packet["_source"]["layers"]):
            header = dg.get("Header", {})
            if num(header.get("ecat.cmd", "0")) != 5:  # FPWR
                continue
            if num(dg.get("ecat.cnt", "0")) != 0:  # returned copy: the master's copy says it
                continue
            station, ado = num(header["ecat.adp"]), num(header["ecat.ado"])
            slave = slaves.setdefault(station, {"fmmu": {}, "sm": {}})
            for i, tree in enumerate(as_list(dg.get("ecat.fmmu_tree", []))):
                n = (ado - 0x0600) // 16 + i
                slave["fmmu"][n] = (num(tree["ecat.fmmu.lstart"]), num(tree["ecat.fmmu.llen"]),
                                    num(tree["ecat.fmmu.pstart"]), num(tree["ecat.fmmu.type"]),
                                    num(tree["ecat.fmmu.activate"]) & 1)
            for i, tree in enumerate(as_list(dg.get("ecat.syncman_tree", []))):
                n = (ado - 0x0800) // 8 + i
                slave["sm"][n] = (num(tree["ecat.syncman.start"]), num(tree["ecat.syncman.len"]))
    for station in sorted(slaves):
        s = slaves[station]
        parts = [f"station 0x{station:04X}"]
        for n in sorted(s["sm"]):
            start, length = s["sm"][n]
            if length:
                parts.append(f"SM{n} 0x{start:04X}+{length}")
        for n in sorted(s["fmmu"]):
            lstart, llen, pstart, ftype, active = s["fmmu"][n]
            if llen or active:
                kind = {1: "read", 2: "write"}.get(ftype, "read/write")
                parts.append(f"FMMU{n} 0x{lstart:08X}+{llen} -> 0x{pstart:04X} {kind}"
                             + ("" if active else " (off)"))
        if len(parts) > 1:
            print("; ".join(parts))


main()

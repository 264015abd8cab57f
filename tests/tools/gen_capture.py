#!/usr/bin/env python3
"""Generate an NC <-> servo EtherCAT capture with a known truth.

An independent oracle for the decoders: written from PROTOCOL.md (sections 1-5, 8 and the
default layout of 9.4) alone, it imports nothing from the project.

Every cycle the master sends one frame -- an LRW of n*10 output bytes followed by n*40 input
bytes at logical 0x00010000, then an FRMW reading the DC system time (0x0910) -- and the ring
returns it a little later with the drives' inputs and the working counters filled in.
Each axis runs a commissioning session: enable, zero-pulse search (incremental axes), motion,
a parameter-table change, a reversal, one drive fault with error clearing (one axis), and an
emergency stop near the end.  The output is a pure function of the options.

The clean session conforms to every rule of RULES.md with its default timeouts at any cycle
time from 125 us to 10 ms: the drive answers every handshake within 10 ms of capture time
(half the shortest timeout), whatever the cycle time, and the one drive fault is reported and
handled correctly (cause and summary bits together, disabled in time, ErrorClear/ErrClearAck,
re-enable by SE 0x1 -> 0x2), which RULES.md says is not a finding.

    gen_capture.py --axes 4 --cycles 2000 -o out.pcap --truth out.jsonl
"""

import argparse
import itertools
import math
import operator
import random
import struct
import sys

# --- SCW bits (PROTOCOL.md section 2) ---
SCW_SE = 0x3
SCW_EMGON = 1 << 2
SCW_PRMTBL_SHIFT = 4
SCW_ERROR_CLEAR = 1 << 9
SCW_BRAKE = 1 << 10
SCW_ZPULSE_REQUEST = 1 << 11
SCW_EXT_PRMTBL_SHIFT = 12

# --- SSW bits (section 3) ---
SSW_SERVO_EN = 1 << 0
SSW_SERVO_RDY = 1 << 1
SSW_INCREMENTAL = 1 << 2
SSW_ZPULSE_ACK = 1 << 3
SSW_ERR_CLEAR_ACK = 1 << 4
SSW_N_ZERO = 1 << 5
SSW_N_SETPOINT = 1 << 6
SSW_PULSE_ENABLED = 1 << 7
SSW_PRMTBL_SHIFT = 8
SSW_EXT_PRMTBL_SHIFT = 12

# --- SEW bits (section 4) ---
SEW_SERVO_ERRORS = 1 << 0
SEW_FOLLOWING = 1 << 19

# A conforming drive answers a handshake within this much capture time, whatever the cycle time:
# half the shortest RULES.md timeout (drive_response, 20 ms), so that even the observation a cycle
# late stays inside it.
RESPONSE_BUDGET_US = 10_000
# drive timers that answer the NC under a timeout (not "zpulse": finding the pulse takes a motion)
ANSWERS = frozenset(("enable", "disable", "zpulse_ack_off", "clear", "err_clear_ack_off",
                     "table"))

# --- EtherCAT (section 8) ---
ETHERTYPE_ECAT = 0x88A4
ECAT_UDP_PORT = 34980
CMD_LRW = 12
CMD_FRMW = 14
LOGICAL_ADDRESS = 0x00010000
DC_ADP, DC_ADO = 0x1001, 0x0910
LEN_MORE = 0x8000
RX_SIZE, TX_SIZE = 10, 40
MAX_AXES = 29

MASTER_MAC = bytes.fromhex("000000000001")
RETURNED_MAC = bytes.fromhex("020000000001")  # slaves set the locally-administered bit
BROADCAST_MAC = b"\xff" * 6

T0_NS = 1_704_067_200 * 10**9  # capture start, 2024-01-01 00:00:00 UTC
DC_EPOCH_OFFSET_NS = 946_684_800 * 10**9  # DC time counts from 2000-01-01

# --- drive model constants (plausible values, not from the spec) ---
SPEED_UNIT_PER_RPM = 100  # SSP in 0.01 rpm
ABS_COUNTS_PER_REV = 1 << 24  # EnDat single-turn resolution
INCR_COUNTS_PER_REV = 1 << 14  # 4096-line encoder, quadrature
N_ZERO_LIMIT = 50  # 0.5 rpm standstill threshold
N_SET_ABS, N_SET_REL = 300, 0.02  # speed-reached tolerance: 3 rpm or 2 %
RATED_CURRENT_A = 8.0
TORQUE_CONSTANT = 1.6  # Nm/A
BUS_VOLTAGE = 560.0
AMBIENT_C = 38.0

RX_KEYS = ("ssp", "scw", "ext_code")
TX_KEYS = ("actpos", "ssw", "sew", "msg_code", "msg_data",
           "ext_data1", "ext_data2", "ext_data3", "ext_data4")
FLOAT_KEYS = ("msg_data", "ext_data1", "ext_data2", "ext_data3", "ext_data4")


def wrap32(value):
    """Two's-complement wrap of an int to int32, as a 32-bit register would hold it."""
    return (value + 2**31) % 2**32 - 2**31


class Plan:
    """When each phase of one axis's session starts, scaled to the run length."""

    def __init__(self, axis, n_axes, cycles, rng):
        stagger = axis * max(1, cycles // (20 * n_axes))
        self.enable = max(3, cycles // 50) + stagger
        self.table_change = int(cycles * 0.35) + stagger
        self.reverse = int(cycles * 0.45) + stagger
        fault_axis = 1 if n_axes > 1 else 0
        self.fault = int(cycles * 0.55) if axis == fault_axis else None
        self.estop = int(cycles * 0.85)  # the NC stops every axis at once
        self.ramp_cycles = min(200, max(5, cycles // 40))
        self.ext_code_period = max(10, cycles // 20)
        self.speeds = self._speeds(axis, rng)
        self.creep = 3000 if self.speeds[0] > 0 else -3000
        # ExtPRMTBL*4 + PRMTBL, i.e. the table number - 1; axis 0 uses ExtPRMTBL
        self.table = rng.randint(4, 7) if axis == 0 else rng.randint(1, 7)

    @staticmethod
    def _speeds(axis, rng):
        """Speed before and after the reversal, in 0.01 rpm; axis 0 goes beyond 16 bits."""
        magnitude = rng.randint(100_000, 300_000) if axis == 0 else rng.randint(20_000, 250_000)
        first = magnitude if (axis // 2) % 2 == 0 else -magnitude
        return first, -round(first * rng.uniform(0.4, 0.9))


class Nc:
    """The NC's side of one axis.

    The session is a script run as a generator, one step per cycle; it sees the drive only
    through the last returned copy it received.  A drive fault interrupts the script with the
    recovery sequence, after which the script resumes where it was.
    """

    def __init__(self, axis, plan, rng):
        self.plan = plan
        self.rng = rng
        self.incremental = axis % 2 == 1
        self.se = 0
        self.emgon = True
        self.zpulse_request = False
        self.error_clear = False
        self.table = 0
        self.ssp = 0
        self.target = 0
        self.ramp = max(1, max(abs(s) for s in plan.speeds) // plan.ramp_cycles)
        self.ext_code = 0
        self.ssw = 0  # last inputs received
        self.sew = 0
        self.k = 0
        self.recovering = False
        self.done = False
        self.scripts = [self._session()]

    def observe(self, ssw, sew):
        self.ssw, self.sew = ssw, sew

    def step(self, k):
        """Outputs (SSP, SCW, ext code) of cycle k."""
        self.k = k
        if self.sew & SEW_SERVO_ERRORS and not self.recovering:
            self.recovering = True
            self.scripts.append(self._recover())
        self._run_script()
        self._ramp_ssp()
        if k % self.plan.ext_code_period == 0 and k:
            self.ext_code = self.rng.choice((-12, -3, -1, 0, 1, 2, 5, 7, 40))
        scw = (self.se | SCW_BRAKE
               | (SCW_EMGON if self.emgon else 0)
               | ((self.table & 3) << SCW_PRMTBL_SHIFT)
               | ((self.table >> 2) << SCW_EXT_PRMTBL_SHIFT)
               | (SCW_ERROR_CLEAR if self.error_clear else 0)
               | (SCW_ZPULSE_REQUEST if self.zpulse_request else 0))
        return self.ssp, scw, self.ext_code

    def _run_script(self):
        while True:
            try:
                next(self.scripts[-1])
                return
            except StopIteration:  # only the recovery ends; the session idles forever
                self.scripts.pop()

    def _ramp_ssp(self):
        """The NC's set-point generator: a linear ramp towards the target speed."""
        delta = self.target - self.ssp
        self.ssp += max(-self.ramp, min(self.ramp, delta))

    # --- script primitives: each yield is one cycle ---
    def _hold(self, cycles):
        for _ in range(cycles):
            yield

    def _until_cycle(self, cycle):
        while self.k < cycle:
            yield

    def _until(self, condition):
        while not condition():
            yield

    # --- the session ---
    def _session(self):
        plan = self.plan
        yield from self._until_cycle(plan.enable)
        yield from self._enable()
        if self.incremental:
            yield from self._search_zero_pulse()
        self.target = plan.speeds[0]
        yield from self._until_cycle(plan.table_change)
        self.table = plan.table
        yield from self._until_cycle(plan.reverse)
        self.target = plan.speeds[1]
        yield from self._until_cycle(plan.estop)
        yield from self._emergency_stop()
        self.done = True
        while True:
            yield

    def _enable(self):
        """SE 0 -> 1 -> 2, the only legal enable edge, then wait for the drive."""
        self.se = 1
        yield from self._hold(self.rng.randint(1, 3))
        self.se = 2
        yield from self._until(lambda: self.ssw & SSW_SERVO_EN)

    def _search_zero_pulse(self):
        """ZPulseRequest handshake while creeping; the NC drops the request on the ack."""
        self.target = self.plan.creep
        self.zpulse_request = True
        yield from self._until(lambda: self.ssw & SSW_ZPULSE_ACK)
        self.zpulse_request = False
        yield from self._until(lambda: not self.ssw & SSW_ZPULSE_ACK)

    def _recover(self):
        """Fault reset: disable, ErrorClear handshake, enable again, resume the motion."""
        resume_target = self.target
        self.target = self.ssp = 0
        yield from self._hold(self.rng.randint(1, 3))
        self.se = 0
        yield from self._until(lambda: not self.ssw & SSW_SERVO_EN)
        yield from self._hold(self.rng.randint(2, 5))
        self.error_clear = True
        yield from self._until(lambda: self.ssw & SSW_ERR_CLEAR_ACK)
        self.error_clear = False
        yield from self._until(lambda: not self.ssw & SSW_ERR_CLEAR_ACK)
        yield from self._hold(self.rng.randint(2, 5))
        yield from self._enable()
        self.target = resume_target
        self.recovering = False

    def _emergency_stop(self):
        """EMGON 0: the drive brakes; once at standstill the NC disables the drive."""
        self.emgon = False
        self.target = 0
        yield from self._until(lambda: self.ssw & SSW_N_ZERO)
        yield from self._hold(self.rng.randint(3, 8))
        self.se = 0
        yield from self._until(lambda: not self.ssw & SSW_SERVO_EN)


class Drive:
    """The servo drive of one axis: reacts to the RxPDO it reads, fills in its TxPDO.

    Handshake answers come after a few cycles, kept as timers (name -> due cycle), and never
    later than RESPONSE_BUDGET_US of capture time.  Servo_Ready_Mode is 0: ServoRDY = not
    ServoErrors.
    """

    def __init__(self, axis, plan, cycle_us, rng):
        self.axis = axis
        self.quick = max(1, RESPONSE_BUDGET_US // cycle_us)  # most cycles an answer may take
        self.rng = rng
        self.incremental = axis % 2 == 1
        cpr = INCR_COUNTS_PER_REV if self.incremental else ABS_COUNTS_PER_REV
        self.cpr = cpr
        self.counts_per_unit = cpr * cycle_us * 1e-6 / (60 * SPEED_UNIT_PER_RPM)
        self.pos = float(self._start_position(axis, rng))
        self.speed = 0.0
        # the emergency ramp stops the fastest axis in half the NC's ramp time
        self.emergency_decel = max(abs(s) for s in plan.speeds) / max(3, plan.ramp_cycles // 2)
        self.en = False  # ServoEn and PulseEnabled move together
        self.zpulse_ack = False
        self.zero_pulse = None  # (offset, index, latched position) once found
        self.err_clear_ack = False
        self.table = 0
        self.sew = 0
        self.scw = SCW_EMGON | SCW_BRAKE
        self.temp = AMBIENT_C + rng.uniform(0, 4)
        self.timers = {}
        if plan.fault is not None:
            self.timers["fault"] = plan.fault

    @staticmethod
    def _start_position(axis, rng):
        """Incremental counters start at 0; absolute positions use the 64 bits."""
        if axis % 2:
            return 0
        if axis == 0:
            return 5_000_000_000 + rng.randrange(ABS_COUNTS_PER_REV)  # beyond 2**32
        if axis == 2:
            return -3_000_000_000 - rng.randrange(ABS_COUNTS_PER_REV)
        return rng.randint(-2**40, 2**40)

    def _after(self, name, low, high):
        delay = self.rng.randint(low, high)
        if name in ANSWERS:
            delay = min(delay, self.quick)
        self.timers[name] = self.k + delay

    def step(self, k, ssp, scw):
        """Inputs (ActPos, SSW, SEW, code, data, extra 1..4) of cycle k."""
        self.k = k
        if self.timers:
            self._fire_timers()
        if scw != self.scw:
            self._on_scw_change(self.scw, scw)
            self.scw = scw
        prev_speed = self.speed
        self._move(ssp, scw)
        return self._inputs(k, ssp, self.speed - prev_speed)

    # --- reactions ---
    def _fire_timers(self):
        for name, due in list(self.timers.items()):
            if due <= self.k:
                del self.timers[name]
                getattr(self, "_timer_" + name)()

    def _on_scw_change(self, old, new):
        changed = old ^ new
        if changed & SCW_SE:
            self._on_se(old & SCW_SE, new & SCW_SE)
        if changed & SCW_ZPULSE_REQUEST:
            self._on_zpulse_request(bool(new & SCW_ZPULSE_REQUEST))
        if changed & SCW_ERROR_CLEAR:
            self._on_error_clear(bool(new & SCW_ERROR_CLEAR))
        if changed & ((3 << SCW_PRMTBL_SHIFT) | (1 << SCW_EXT_PRMTBL_SHIFT)):
            self._after("table", 2, 5)

    def _on_se(self, old, new):
        if old == 1 and new == 2:  # the only enabling edge
            if not self.sew:
                self._after("enable", 2, 5)
        elif old == 2:
            self.timers.pop("enable", None)
            if self.en:
                self._after("disable", 1, 3)

    def _on_zpulse_request(self, on):
        if on:
            self._after("zpulse", 5, 20)
        else:
            self.timers.pop("zpulse", None)
            if self.zpulse_ack:
                self._after("zpulse_ack_off", 2, 5)

    def _on_error_clear(self, on):
        if on and self.sew:
            self._after("clear", 2, 5)
        elif not on and self.err_clear_ack:
            self._after("err_clear_ack_off", 2, 5)

    # --- timer actions ---
    def _timer_enable(self):
        if not self.sew:
            self.en = True

    def _timer_disable(self):
        self.en = False

    def _timer_zpulse(self):
        """Zero pulse found here; later ones are one revolution apart."""
        self.zpulse_ack = True
        position = round(self.pos)
        offset = position % self.cpr
        self.zero_pulse = (offset, (position - offset) // self.cpr, position)

    def _timer_zpulse_ack_off(self):
        self.zpulse_ack = False

    def _timer_clear(self):
        self.sew = 0
        self.err_clear_ack = True

    def _timer_err_clear_ack_off(self):
        self.err_clear_ack = False

    def _timer_table(self):
        scw = self.scw
        self.table = ((scw >> SCW_PRMTBL_SHIFT) & 3) | (((scw >> SCW_EXT_PRMTBL_SHIFT) & 1) << 2)

    def _timer_fault(self):
        """Following error: ServoRDY drops at once, the power stage a few cycles later."""
        self.sew = SEW_FOLLOWING | SEW_SERVO_ERRORS
        self.timers.pop("enable", None)
        self._after("disable", 1, 3)

    # --- physics ---
    def _move(self, ssp, scw):
        if not self.en:
            self.speed *= 0.9  # coasting
        elif scw & SCW_EMGON:
            self.speed += (ssp - self.speed) * 0.3  # speed regulator lag
        else:  # emergency ramp to Emergency Feed = 0
            self.speed = math.copysign(max(0.0, abs(self.speed) - self.emergency_decel), self.speed)
        if abs(self.speed) < 1:
            self.speed = 0.0
        self.pos += self.speed * self.counts_per_unit
        if self.zero_pulse:
            self._track_zero_pulses()

    def _track_zero_pulses(self):
        """Latch the position of the zero pulse passed in this cycle, if any."""
        offset, index, _ = self.zero_pulse
        new_index = math.floor((self.pos - offset) / self.cpr)
        if new_index != index:
            crossed = max(index, new_index)
            self.zero_pulse = (offset, new_index, offset + crossed * self.cpr)

    def _actpos(self):
        position = round(self.pos)
        if not self.incremental:
            return position
        latched = wrap32(self.zero_pulse[2]) if self.zero_pulse else 0
        return (latched << 32) | (position & 0xFFFFFFFF)

    def _ssw(self, ssp):
        speed = self.speed
        in_tolerance = abs(ssp - speed) <= max(N_SET_ABS, abs(ssp) * N_SET_REL)
        return ((SSW_SERVO_EN | SSW_PULSE_ENABLED if self.en else 0)
                | (0 if self.sew else SSW_SERVO_RDY)
                | (SSW_INCREMENTAL if self.incremental else 0)
                | (SSW_ZPULSE_ACK if self.zpulse_ack else 0)
                | (SSW_ERR_CLEAR_ACK if self.err_clear_ack else 0)
                | (SSW_N_ZERO if abs(speed) < N_ZERO_LIMIT else 0)
                | (SSW_N_SETPOINT if in_tolerance else 0)
                | ((self.table & 3) << SSW_PRMTBL_SHIFT)
                | ((self.table >> 2) << SSW_EXT_PRMTBL_SHIFT))

    def _inputs(self, k, ssp, accel):
        rnd = self.rng.random
        rpm = self.speed / SPEED_UNIT_PER_RPM + ((rnd() - 0.5) * 0.2 if self.speed else 0.0)
        if self.en:
            friction = 0.4 if self.speed > 0 else -0.4 if self.speed < 0 else 0.0
            current = friction + accel * 2e-4 + self.speed * 2e-6 + (rnd() - 0.5) * 0.05
        else:
            current = 0.0
        torque = current * TORQUE_CONSTANT
        power_kw = rpm * torque * (2 * math.pi / 60) / 1000
        self.temp += (AMBIENT_C + 0.8 * current * current - self.temp) * 1e-4
        vbus = BUS_VOLTAGE + (rnd() - 0.5) * 4 - 0.3 * abs(current)
        code = (k + self.axis) % 6
        data = (rpm, abs(current), abs(current) / RATED_CURRENT_A * 100,
                vbus, self.temp, power_kw)[code]
        following = ssp / SPEED_UNIT_PER_RPM - rpm
        return (self._actpos(), self._ssw(ssp), self.sew, code, data,
                following, torque, current, self.temp + 6.5)


# --- frames ---
def link_header(encap, src_mac, payload_len):
    """Ethernet (+ VLAN tags, or IPv4/UDP) in front of the EtherCAT frame header."""
    eth = BROADCAST_MAC + src_mac
    if encap == "eth":
        return eth + struct.pack(">H", ETHERTYPE_ECAT)
    if encap == "vlan":
        return eth + struct.pack(">HHH", 0x8100, 5, ETHERTYPE_ECAT)
    if encap == "qinq":
        return eth + struct.pack(">HHHHH", 0x88A8, 100, 0x8100, 5, ETHERTYPE_ECAT)
    udp_len = 8 + payload_len
    ip = ipv4_header(20 + udp_len, bytes((192, 168, 1, 1)), bytes((255, 255, 255, 255)))
    udp = struct.pack(">HHHH", ECAT_UDP_PORT, ECAT_UDP_PORT, udp_len, 0)  # checksum 0 = none
    return eth + struct.pack(">H", 0x0800) + ip + udp


def ipv4_header(total_len, src, dst):
    header = struct.pack(">BBHHHBBH4s4s", 0x45, 0, total_len, 0, 0x4000, 64, 17, 0, src, dst)
    total = sum(struct.unpack(">10H", header))
    total = (total & 0xFFFF) + (total >> 16)
    total = (total & 0xFFFF) + (total >> 16)
    return header[:10] + struct.pack(">H", ~total & 0xFFFF) + header[12:]


class FrameBuilder:
    """Packs the master and returned copies of one cycle's frame."""

    def __init__(self, n_axes, encap):
        self.rx = struct.Struct("<" + "iIh" * n_axes)
        self.tx = struct.Struct("<" + "qIIif4f" * n_axes)
        lrw_len = n_axes * (RX_SIZE + TX_SIZE)
        # frame header, LRW header, outputs, inputs, WKC, FRMW header, DC time, WKC
        self.body = struct.Struct(f"<H BBIHH {n_axes * RX_SIZE}s {n_axes * TX_SIZE}s H "
                                  "BBHHHH Q H")
        chain_len = self.body.size - 2
        self.ecat_header = chain_len | (1 << 12)
        self.lrw_len_word = lrw_len | LEN_MORE
        self.n_axes = n_axes
        self.zero_inputs = bytes(n_axes * TX_SIZE)
        self.prefix_master = link_header(encap, MASTER_MAC, self.body.size)
        self.prefix_returned = link_header(encap, RETURNED_MAC, self.body.size)
        self.pad = bytes(max(0, 60 - len(self.prefix_master) - self.body.size))

    def frame(self, returned, index, outputs, inputs, dc_time):
        n = self.n_axes
        body = self.body.pack(self.ecat_header,
                              CMD_LRW, index, LOGICAL_ADDRESS, self.lrw_len_word, 0,
                              outputs, inputs, 3 * n if returned else 0,
                              CMD_FRMW, index, DC_ADP, DC_ADO, 8, 0,
                              dc_time, n if returned else 0)
        prefix = self.prefix_returned if returned else self.prefix_master
        return prefix + body + self.pad


class PcapWriter:
    def __init__(self, out, nanosecond):
        self.out = out
        self.divisor = 1 if nanosecond else 1000
        self.record = struct.Struct("<IIII")
        magic = 0xA1B23C4D if nanosecond else 0xA1B2C3D4
        out.write(struct.pack("<IHHiIII", magic, 2, 4, 0, 0, 65535, 1))

    def write(self, t_ns, data):
        sec, frac = divmod(t_ns, 10**9)
        self.out.write(self.record.pack(sec, frac // self.divisor, len(data), len(data)))
        self.out.write(data)


class PcapngWriter:
    def __init__(self, out):
        self.out = out
        self.epb = struct.Struct("<IIIIIII")
        shb_body = struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1)
        self._block(0x0A0D0D0A, shb_body)
        tsresol = struct.pack("<HHB3x", 9, 1, 9)  # if_tsresol = 10^-9
        idb_body = struct.pack("<HHI", 1, 0, 65535) + tsresol + struct.pack("<HH", 0, 0)
        self._block(1, idb_body)

    def _block(self, block_type, body):
        total = 12 + len(body)
        self.out.write(struct.pack("<II", block_type, total) + body + struct.pack("<I", total))

    def write(self, t_ns, data):
        pad = -len(data) % 4
        total = 32 + len(data) + pad
        self.out.write(self.epb.pack(6, total, 0, t_ns >> 32, t_ns & 0xFFFFFFFF,
                                     len(data), len(data)))
        self.out.write(data + bytes(pad) + struct.pack("<I", total))


class TruthWriter:
    """One JSON line per written frame; values are read back from the packed bytes.

    Lines come from %-templates built once (json.dumps per frame would dominate the run time
    of a million-frame capture); floats are written with repr, as json does.
    """

    def __init__(self, out, builder):
        self.out = out
        self.rx = builder.rx
        self.tx = builder.tx
        n = builder.n_axes
        self.master_line = self._template(n, "master", False)
        self.returned_line = self._template(n, "returned", True)
        # the returned line lists each axis's RxPDO then TxPDO: regroup the unpacked values
        per_axis = [list(range(3 * i, 3 * i + 3))
                    + list(range(3 * n + 9 * i, 3 * n + 9 * i + 9)) for i in range(n)]
        self.by_axis = operator.itemgetter(*itertools.chain.from_iterable(per_axis))
        self.frame_number = 0
        self.first_ns = None

    @staticmethod
    def _template(n_axes, copy, with_inputs):
        keys = RX_KEYS + TX_KEYS if with_inputs else RX_KEYS
        fields = ",".join(f'"{key}":{"%r" if key in FLOAT_KEYS else "%d"}' for key in keys)
        axes = ",".join(f'{{"axis":{i},{fields}}}' for i in range(n_axes))
        return f'{{"frame":%d,"time":%r,"copy":"{copy}","axes":[{axes}]}}\n'

    def write(self, t_ns, copy, outputs, inputs):
        self.frame_number += 1
        if self.first_ns is None:
            self.first_ns = t_ns
        head = (self.frame_number, (t_ns - self.first_ns) / 1e9)
        if copy == "returned":
            values = self.by_axis(self.rx.unpack(outputs) + self.tx.unpack(inputs))
            line = self.returned_line % (head + values)
        else:
            line = self.master_line % (head + self.rx.unpack(outputs))
        self.out.write(line)


class Session:
    """All axes of the run, stepped one cycle at a time."""

    def __init__(self, args):
        self.ncs, self.drives = [], []
        for axis in range(args.axes):
            plan = Plan(axis, args.axes, args.cycles, random.Random(f"{args.seed}/plan/{axis}"))
            self.ncs.append(Nc(axis, plan, random.Random(f"{args.seed}/nc/{axis}")))
            self.drives.append(Drive(axis, plan, args.cycle_us,
                                     random.Random(f"{args.seed}/drive/{axis}")))

    def step(self, k):
        """Flat output and input values of every axis for cycle k."""
        outputs = [nc.step(k) for nc in self.ncs]
        inputs = [drive.step(k, o[0], o[1]) for drive, o in zip(self.drives, outputs)]
        return outputs, inputs

    def deliver(self, inputs):
        """The returned copy reached the master: the NCs see the new status."""
        for nc, values in zip(self.ncs, inputs):
            nc.observe(values[1], values[2])

    def complete(self):
        return all(nc.done for nc in self.ncs)


def generate(args, out, truth_out):
    builder = FrameBuilder(args.axes, args.encap)
    writer = PcapngWriter(out) if args.format == "pcapng" else PcapWriter(out, args.nanosecond)
    truth = TruthWriter(truth_out, builder) if truth_out else None
    session = Session(args)
    loss_rng = random.Random(f"{args.seed}/loss")
    cycle_ns, delay_ns = args.cycle_us * 1000, args.return_delay_us * 1000
    dc_start = T0_NS - DC_EPOCH_OFFSET_NS + 1234  # reference clock slightly off the host clock
    want_master = args.copies in ("both", "master")
    want_returned = args.copies in ("both", "returned")
    chain = itertools.chain.from_iterable
    for k in range(args.cycles):
        outputs, inputs = session.step(k)
        out_bytes = builder.rx.pack(*chain(outputs))
        t_ns = T0_NS + k * cycle_ns
        index = k & 0xFF
        if want_master:
            writer.write(t_ns, builder.frame(False, index, out_bytes, builder.zero_inputs, 0))
            if truth:
                truth.write(t_ns, "master", out_bytes, None)
        if args.loss and loss_rng.random() < args.loss:
            continue
        session.deliver(inputs)
        if want_returned:
            in_bytes = builder.tx.pack(*chain(inputs))
            t_ret = t_ns + delay_ns
            frame = builder.frame(True, index, out_bytes, in_bytes, dc_start + t_ret - T0_NS)
            writer.write(t_ret, frame)
            if truth:
                truth.write(t_ret, "returned", out_bytes, in_bytes)
    return session.complete()


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--axes", type=int, default=4, help="servo axes, 1..29 (default 4)")
    p.add_argument("--cycles", type=int, default=2000, help="cycles, at least 200 (default 2000)")
    p.add_argument("--cycle-us", type=int, default=1000, help="cycle time in us (default 1000)")
    p.add_argument("--return-delay-us", type=int, default=20,
                   help="returned copy after the master copy, us (default 20)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--encap", choices=("eth", "vlan", "qinq", "udp"), default="eth")
    p.add_argument("--format", choices=("pcap", "pcapng"), default="pcap")
    p.add_argument("--nanosecond", action="store_true", help="pcap with nanosecond timestamps")
    p.add_argument("--copies", choices=("both", "master", "returned"), default="both")
    p.add_argument("--loss", type=float, default=0.0,
                   help="probability of losing a returned copy (default 0)")
    p.add_argument("-o", "--output", required=True, help="capture file to write")
    p.add_argument("--truth", help="JSON Lines truth file to write")
    args = p.parse_args(argv)
    if not 1 <= args.axes <= MAX_AXES:
        p.error("--axes must be 1..29 (one LRW of at most 1486 bytes)")
    if args.cycles < 200:
        p.error("--cycles must be at least 200 for the session to fit")
    if not 0 < args.return_delay_us < args.cycle_us:
        p.error("--return-delay-us must be positive and below --cycle-us")
    if not 0 <= args.loss < 1:
        p.error("--loss must be in [0, 1)")
    if args.encap == "udp" and args.axes > 28:
        print("gen_capture: warning: frames of more than 28 axes in UDP exceed the Ethernet MTU",
              file=sys.stderr)
    return args


def main(argv=None):
    args = parse_args(argv)
    truth_out = open(args.truth, "w", encoding="ascii", buffering=1 << 20) if args.truth else None
    try:
        with open(args.output, "wb", buffering=1 << 20) as out:
            complete = generate(args, out, truth_out)
    finally:
        if truth_out:
            truth_out.close()
    if not complete:
        print("gen_capture: the session did not finish in --cycles cycles", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

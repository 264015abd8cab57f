#!/usr/bin/env python3
"""Generate an NC <-> servo EtherCAT capture with a known truth.

An independent oracle for the decoders: written from the protocol's definition (docs/protocol.md
§1-5, §8 and the outputs-first layout of §9.4; PROTOCOL.md §11 for the mailbox and the ESCs'
registers) alone, it imports nothing from the project.

Every cycle the master sends one frame -- an LRW of n*10 output bytes followed by n*40 input
bytes at logical 0x00010000, then an FRMW reading the DC system time (0x0910) -- and the ring
returns it a little later with the drives' inputs and the working counters filled in.
Each axis runs a commissioning session: enable, zero-pulse search (incremental axes), motion,
a parameter-table change, a reversal, one drive fault with error clearing (one axis), and an
emergency stop near the end.  The output is a pure function of the options.

    gen_capture.py --axes 4 --cycles 2000 -o out.pcap --truth out.jsonl

The clean session conforms to every rule of docs/rules.md with its default timeouts at any cycle
time from 125 us to 10 ms: the drive answers every handshake within 10 ms of capture time
(half the shortest timeout), whatever the cycle time, and the one drive fault is reported and
handled correctly (cause and summary bits together, disabled in time, ErrorClear/ErrClearAck,
re-enable by SE 0x1 -> 0x2), which is not a finding (docs/protocol.md §4).

Shapes of a machine's bus (the layout then has to be found without a start-up, as on a running
machine; --layout-config writes the exact one for `validate --config`):

--io-terminals N / --cia402 N
    neighbours before the servos in their LRW: N I/O terminals of one output and one input byte
    whose inputs change every cycle (an odd N puts every servo PDO at an odd offset), N CiA 402
    drives whose PDOs have a servo's 10 and 40 bytes.
--idle-cycles N / --idle-all
    the drives ready and nothing enabled for the first N cycles (the session runs in the rest),
    or in the whole capture (no drive fault either; no --inject).
--io-task-cycles N
    a second task: after every N-th cycle's frame, an I/O frame with its own LRW at 0x00020000
    (both copies); no bus (COM-*) injection beside it.
--echo-inputs
    master copies carry the inputs of the last returned copy, as a SOEM master's do.

What the capturing PC does to the recording (docs/simulate.md#the-capturing-pc; `ncservo
simulate` has options of the same names, written apart from these): the frames, their bytes and
order and the DC system time they carry stay the bus's, and so do the truth, the findings' windows
and the incidents (their frame numbers count the capture's records, the original of a mirrored
copy).

--capture-stamps SHAPE:LENGTH   (LENGTH in us or ms)
    bunched:4ms    the NIC coalesces interrupts: every record is stamped at the end of its burst
                   window (the capture clock cut in windows of LENGTH from the epoch), the records
                   of a burst 2 us apart in capture order (100 us to 100 ms)
    quantised:1ms  a coarse clock: every stamp floored to a multiple of LENGTH (1 us to 100 ms)
    late:400us     every stamp late by a random whole number of us from 0 to LENGTH, then never
                   before the stamp before it (1 us to 10 ms)
--duplicate-records
    every record twice, the copy right after its original with the same bytes, stamped 1 us
    later (the same stamp under quantised stamps), as a switch port mirroring both directions
--second-interface
    pcapng only: interface 1, Linux cooked (LINKTYPE_LINUX_SLL, 113), carries the PC's office
    port: ARP requests and UDP datagrams of the PC and its neighbours, 0.5 to 7 ms apart,
    between the EtherCAT records (interface 0, Ethernet) by time

It is also the oracle for the rule engine (`ncservo validate`):

--ready-mode 0|1
    the drives' Servo_Ready_Mode (docs/protocol.md §5; default 0).
--inject RULE[@SECONDS][:AXIS]   (repeatable)
    inject one violation of RULE at SECONDS after the capture's first frame on AXIS.  Without
    @SECONDS the rule's default place in the session (a fraction of its length) is used, without
    :AXIS the rule's default axis (an incremental one, odd index, for ZP-001; an absolute one,
    even index, for ZP-003).  An injection starts at the first cycle from then on where its axis is
    enabled and idle (no handshake, fault or emergency stop under way); injections on one axis run
    one after another, those on different axes may overlap, and a bus injection (COM-*) waits
    until every axis is idle and runs alone.  The NC's session pauses while its axis is under an
    injection and then carries on, so the session needs room: about 0.3 s per injection on one
    axis (cycles x cycle time of at least 2 s for all of them at once).
    NC rules (SE-001, ZP-003, EC-002, SCW-001) change the NC's outputs, drive rules the drive's
    inputs, bus rules the frames.  Every timed violation holds for twice its timeout and then ends
    cleanly; every momentary one is kept short enough not to become a second, timed finding.
      SE-001  SE 0x0 -> 0x2 (after a legal disable); the drive stays off; legal re-enable
      SE-002  ServoEn rises with SE 0 held for 2 x drive_response, for at most drive_response / 4
      SE-003  SE 2 -> 0, ServoEn stays 1 for 2 x drive_response
      SE-004  legal SE 0x1 -> 0x2 while ready, ServoEn follows only after 2 x enable_response
      ZP-001  zero-pulse handshake, ZPulseAck stays 2 x drive_response after the request fell
      ZP-002  ZPulseAck for at most drive_response / 4 with no request for 2 x drive_response
      ZP-003  ZPulseRequest on an absolute axis for 2 x drive_response (the drive ignores it)
      EC-001  ErrClearAck for at most drive_response / 4, ErrorClear 0 for 2 x drive_response
      EC-002  ErrorClear (no error pending) held 2 x nc_release after ErrClearAck
      EC-003  ErrClearAck stays 2 x drive_response after ErrorClear fell
      EC-004  overload fault; the drive acknowledges ErrorClear only after 2 x clear_response
      SEW-001 I2t_Endat cause bit without the summary bit for 2 x drive_response
      SEW-002 fault with the summary bit and no cause; cleared no earlier than 2 x drive_response
      SEW-003 reserved SEW bit 4 for 2 x drive_response
      SSW-001 reserved SSW bit 13 for 2 x drive_response
      SCW-001 reserved SCW bit 16 for 2 x drive_response
      RDY-001 ServoRDY inverted for 2 x drive_response
      FLT-001 power-stage fault (PDPINT), ServoEn stays 1 for 2 x fault_reaction (the NC keeps
              SE 2 until the drive is off, so SE-003 is not involved)
      PT-001  table change followed only after 2 x param_table, then changed back
      MSG-001 message code 7 for 2 x drive_response
      COM-001 one returned copy with WKC 3n - 1
      COM-002 two consecutive cycles missing from the capture (both copies; the ring worked)
      COM-003 three consecutive frames lost before the drives (master copies only in the
              capture); AXIS's drive does not raise ECatTErr, every other drive does (a correct
              E15 fault, then recovered)
      COM-004 one frame lost before the drives (its master copy only)
      COM-005 four consecutive frames lost before the drives; every drive raises ECatTErr
    What the drives and the ESCs say themselves (PROTOCOL.md §11) is shown by the master's
    acyclic frames, sent between the cycles as SOEM sends them: FPRD/FPWR by station address
    only (no logical datagram: no cycle, WKC or timing rule sees them), none in a cycle lost
    or dropped.  These injections start at SECONDS whatever the axes do; AXIS names the axis's
    drive.  The slaves are in ring order (--io-terminals, --cia402, then the servos) at stations
    0x1001 on.  From the first LNK-* injection on, every slave's error counters (0x0300, 20
    bytes) are polled every 50 ms, the first poll the baseline (a few errors and lost links
    from before the capture); from the first DC-001, every 10 ms, the master writes its time
    into the reference clock (0x0910 of the first slave, as EtherLab does) and reads every
    slave's system time difference (0x092C, sign and magnitude), within +-80 ns.  MBX-003 and
    ERH-001 are SDO transfers in the drive's mailbox (SM0 at 0x1000, SM1 at 0x1080, 128 bytes
    each; no start-up, so the validator finds them from use): the request written in one
    frame, SM1 read in the next cycles, empty (WKC 0) twice, then with the answer.  The
    drive's 1003h holds one entry per SEW cause bit that rose.
      MBX-003 uploads of 1003h:00, of the first entry the drive does not hold (aborted with
              0x08000024: expected, not a finding) and of 2000h:00, aborted with 0x06020000
              (the drive's abort is an SDO request, CoE service 2, as ETG.1000.6 has it)
      ERH-001 the drive holds 3 entries from before the capture; the NC reads 1003h:00, then,
              100 ms later, 1 (the drive lost the others) with no write of 0 between; then
              it clears the history (a download of 0 to 1003h:00) and reads 0: no finding
      LNK-001 4 RX errors at port 0 of the drive, none forwarded (symbol errors between
              frames: no frame lost), at the third poll
      LNK-002 a link-down at port 1 of the drive (default the last slave, the end of the
              line), at the third poll; inside the ring the next slave's port 0 counts it too
              (one finding each)
      DC-001  the drive reads -5.0, -5.2 and -4.9 us in a row after 3 reads in sync, then in
              sync again: one finding, on the first
    A drive's own words against its SEW (the same mailbox; injected on the axis like the
    drive rules, starting when it is idle).  The validator judges them on the axis whose
    station it knows: --layout-config then names each axis's station (--list-station-rules).
      MBX-001 the NC reads 1003h:00 (the mailbox is found from use), then the drive sends an
              emergency 0x8611 with no SEW cause bit for 2 x drive_response; from then on it
              sends an emergency after the cycle that shows each cause bit rising
      MBX-002 the NC reads 1003h:00; the drive, sending an emergency for each fault, has a
              following error (0x8611 after its cycle), the NC recovers, then a second
              following error with no emergency (later faults reported again)
      ERH-002 a following error (0x8611 in PROTOCOL.md section 7); the NC reads 1003h:01 and
              the newest entry carries 0x2300 (number 2, class 0x03): on that read
--findings FILE
    write the findings the injections must produce, as JSON:
      {"expected": [{"rule": "SE-001", "axis": 0, "first_frame": N, "last_frame": M,
                     "due_frame": D}, ...],
       "companions": {"COM-003": ["COM-004"], ...}}
    axis is null for COM-001, COM-002, COM-004 and the §11 rules (MBX-003, ERH-001, LNK-001,
    LNK-002, DC-001: without a start-up the validator does not know an axis's station); MBX-001,
    MBX-002 and ERH-002 name their axis (the layout file names the stations).  Frames
    are 1-based, counting every record.
    The window [first_frame, last_frame] is where the validator may report the finding:
    an immediate finding exactly on the frame that first shows it (the master copy for NC
    outputs, the returned copy for drive inputs and WKC, the first master frame after a gap or
    after a frame that was not returned); a timed one from one cycle before due_frame to two
    cycles after it, due_frame being the first frame more than the timeout after the frame where
    the condition began (docs/timing.md#rule-time): reported before its timeout, it is
    missing.  COM-005: from the master frame of the fourth failed cycle to the returned copy of
    the next.  COM-003: timed like the others, due on the first frame more than drive_response
    after the returned copy of the first master frame after the outage.  The §11 rules: exactly
    the returned copy of the acyclic frame that shows them (ERH-002: the read of 1003h:01);
    MBX-001 timed from the cycle after which the emergency is read, MBX-002 from the returned
    copy showing the unreported cause bit.
    companions lists, per injected rule, other rules it necessarily causes as well (see
    COMPANIONS).  check_findings.py compares a validator's JSON report with this file.
--incident KIND[@SECONDS][:AXIS]   (repeatable)
    a drive fault after the chain of evidence its incident cause needs (`validate`'s incidents),
    run like an injection; the defaults place each on its own axis and time:
      communication-loss          2 cycles lost before the drives (COM-004; under the telegram
                                  failure limit, so no ECatTErr), then ECatWatchDog 3 cycles
                                  later (default 20 % of the session, axis 2)
      link-fault                  the communication-loss chain on a bad cable: the master polls
                                  every slave's ESC error counters (as LNK-001 below), and the
                                  first poll after the fault shows 4 RX errors at the drive's
                                  port 0 that no slave forwarded (LNK-001) (57 %, axis 2)
      overtemperature             the motor temperature (message code 4, extra data 4) climbs at
                                  200 °C/s, SSW.TempWarning above 80 °C, I2t_Endat at 96 °C; the
                                  motor cools after it (30 %, axis 3)
      following-error-after-step  the NC steps the speed set point by 2000 rpm in one cycle;
                                  FollowerErr 25 ms later (40 %, axis 0)
      bus-outage                  8 cycles lost before the drives (no :AXIS): every axis fails
                                  longer than the telegram failure limit (3), and every drive
                                  raises ECatTErr (65 %)
    The NC clears each fault (ErrorClear/ErrClearAck) and enables the axis again.
--incidents FILE
    write every drive fault of the capture as JSON, the truth `ncservo validate` must list:
      {"incidents": [{"kind": "drive-fault", "axis": 2, "frame": N, "cause": "..."}, ...]}
    frame: the returned copy in which the axis's SEW.ServoErrors first reads 1 (1-based, every
    record counted); cause: the chain's kind, "following-error" for the session's own fault
    (axis 1, at a steady set point), "communication-loss" for ECatTErr after lost frames; a bus
    outage is {"kind": "bus-outage", "axis": null, "frame": N, "cause": "communication-loss"}
    on the master copy of the cycle after the limit's (where COM-005 is reported).
    Not with --inject or --loss, and only with both copies.
--self-check
    assert, cycle by cycle, that every axis not under an injection conforms (reserved bits,
    SE edges, SEW summary, ServoRDY table, message codes, and every handshake answered within
    its timeout in capture time); on by default with --findings.

    gen_capture.py --cycles 3000 --inject SE-004 --inject COM-003@1.2:1 \
        -o se004.pcap --findings se004.json
    ncservo validate --format json se004.pcap >report.json
    check_findings.py report.json se004.json
"""

import argparse
import bisect
import itertools
import json
import math
import operator
import random
import struct
import sys

# --- SCW bits (docs/protocol.md §2) ---
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
SSW_TEMP_WARNING = 1 << 11  # motor temperature over 80 °C
SSW_EXT_PRMTBL_SHIFT = 12

SCW_RESERVED = 0x7FFFE000  # bits 13..30

SSW_RESERVED = 0xFFFFE000  # bits 13..31

# --- SEW bits (section 4) ---
SEW_SERVO_ERRORS = 1 << 0
SEW_I2T_ENDAT = 1 << 2
SEW_RESERVED_BIT4 = 1 << 4
SEW_ECAT_TIMEOUT = 1 << 15
SEW_PDPINT = 1 << 16
SEW_FOLLOWING = 1 << 19
SEW_OVERLOAD = 1 << 20
SEW_ECAT_WATCHDOG = 1 << 22
SEW_CAUSES = 0x01FFFFEE  # bits 1..3, 5..24
SEW_RESERVED = 0xFE000010  # bit 4, bits 25..31

# --- rule timeouts (defaults, milliseconds; docs/rules.md) ---
TIMEOUT_MS = {"drive_response": 20, "nc_release": 50, "enable_response": 100,
              "clear_response": 100, "fault_reaction": 100, "param_table": 50}
# A conforming drive answers a handshake within this much capture time, whatever the cycle time:
# half the shortest timeout, so that even the observation a cycle late stays inside it.
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
IO_TASK_ADDRESS = 0x00020000
IO_TASK_BYTES = 4

# --- the mailbox and the ESCs' own registers (section 11) ---
CMD_FPRD, CMD_FPWR = 4, 5
FIRST_STATION = DC_ADP  # slaves' station addresses count up from it in ring order
ERROR_COUNTERS, ERROR_COUNTERS_SIZE = 0x0300, 20  # 0x0300-0x0313
INVALID_FRAME, RX_ERROR, FORWARDED, LOST_LINK = 0x0300, 0x0301, 0x0308, 0x0310  # port 0
DC_DIFFERENCE = 0x092C
DC_SMALLER = 1 << 31  # sign and magnitude: set when the slave's copy is smaller
MBX_OUT, MBX_IN, MBX_SIZE = 0x1000, 0x1080, 128  # SM0 (master -> drive) and SM1 areas
MBX_COE = 3
COE_EMERGENCY, COE_SDO_REQUEST, COE_SDO_RESPONSE = 1, 2, 3
# PROTOCOL.md section 7: the CANopen code of each SEW cause bit, as this project maps it
CANOPEN_CODE = {1 << bit: code for bits, code in (
    ((1,), 0x7305), ((2,), 0x4200), ((3, 13, 14, 22), 0x8100), ((5,), 0x3100),
    ((6, 7, 16, 20, 24), 0x2300), ((8, 9), 0x7306), ((10,), 0x6010), ((11, 12, 15), 0x8130),
    ((17,), 0x6320), ((18,), 0x6100), ((19,), 0x8611), ((21,), 0x7600), ((23,), 0x8400))
    for bit in bits}
SDO_DOWNLOAD, SDO_UPLOAD, SDO_ABORT = 1 << 5, 2 << 5, 4 << 5  # request specifiers
SDO_UPLOADED, SDO_DOWNLOADED = 2 << 5, 3 << 5  # response specifiers
SDO_EXPEDITED, SDO_SIZE_INDICATED = 0x02, 0x01
ERROR_FIELD = 0x1003  # pre-defined error field: subindex 0 the number of entries
ABORT_NO_DATA, ABORT_NO_OBJECT = 0x08000024, 0x06020000
MAX_FRAME_DATAGRAMS = 1470  # bytes of datagrams in one frame (fits UDP in a 1500-byte MTU)

MASTER_MAC = bytes.fromhex("000000000001")
RETURNED_MAC = bytes.fromhex("020000000001")  # slaves set the locally-administered bit
BROADCAST_MAC = b"\xff" * 6

T0_NS = 1_704_067_200 * 10**9  # capture start, 2024-01-01 00:00:00 UTC
LINKTYPE_ETHERNET, LINKTYPE_LINUX_SLL = 1, 113  # tcpdump.org link types
DC_EPOCH_OFFSET_NS = 946_684_800 * 10**9  # DC time counts from 2000-01-01
DC_REFERENCE_OFF_NS = 1234  # the reference clock slightly off the host clock

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
TEMP_WARNING_C = 80.0
COOLING_S = 1.0  # after an overtemperature fault the motor cools with this time constant

RX_KEYS = ("ssp", "scw", "ext_code")
TX_KEYS = ("actpos", "ssw", "sew", "msg_code", "msg_data",
           "ext_data1", "ext_data2", "ext_data3", "ext_data4")
FLOAT_KEYS = ("msg_data", "ext_data1", "ext_data2", "ext_data3", "ext_data4")


def wrap32(value):
    """Two's-complement wrap of an int to int32, as a 32-bit register would hold it."""
    return (value + 2**31) % 2**32 - 2**31


class Plan:
    """When each phase of one axis's session starts, scaled to the run length."""

    def __init__(self, axis, n_axes, cycles, rng, enable_by=None, idle=0, idle_all=False):
        self.idle_all = idle_all
        cycles -= idle  # the session runs in what the idle start leaves
        stagger = axis * max(1, cycles // (20 * n_axes))
        self.enable = max(3, cycles // 50) + stagger
        if enable_by is not None:  # the same staggered enables, squeezed into [B/4, 3B/4)
            self.enable = max(3, enable_by // 4) + axis * max(1, enable_by // (2 * n_axes))
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
        self.enable += idle
        self.table_change += idle
        self.reverse += idle
        self.estop += idle
        if self.fault is not None:
            self.fault = None if idle_all else self.fault + idle

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
        self.recoveries = 0  # fault resets done
        self.done = False
        self.scripts = [self._session()]
        # set by injections only (--inject): extra SCW bits, the running injection, and a
        # recovery that leaves SE 2 until the drive has disabled itself
        self.extra_scw = 0
        self.injection = None
        self.recover_waits_for_disable = False

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
               | (SCW_ZPULSE_REQUEST if self.zpulse_request else 0)
               | self.extra_scw)
        return self.ssp, scw, self.ext_code

    def active_table(self):
        """The drive's active table (ExtPRMTBL*4 + PRMTBL) in the last inputs received."""
        ssw = self.ssw
        return ((ssw >> SSW_PRMTBL_SHIFT) & 3) | (((ssw >> SSW_EXT_PRMTBL_SHIFT) & 1) << 2)

    def settled(self):
        """Enabled and idle as far as the NC can tell: no handshake, fault, emergency or
        table change under way, so an injection can start (and has ended)."""
        ssw = self.ssw
        return bool(self.se == 2 and ssw & SSW_SERVO_EN and not self.sew and self.emgon
                    and not (self.recovering or self.done or self.zpulse_request
                             or self.error_clear or self.extra_scw)
                    and not ssw & (SSW_ZPULSE_ACK | SSW_ERR_CLEAR_ACK)
                    and self.active_table() == self.table)

    def _run_script(self):
        while True:
            try:
                next(self.scripts[-1])
                return
            except StopIteration:  # a recovery or an injection ended; the session idles forever
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
        if plan.idle_all:  # drives ready, nothing enabled, to the end
            self.done = True
            while True:
                yield
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
        if self.recover_waits_for_disable:
            yield from self._until(lambda: not self.ssw & SSW_SERVO_EN)
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
        self.recoveries += 1

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
    later than RESPONSE_BUDGET_US of capture time.  ServoRDY follows the Servo_Ready_Mode table:
    mode 0 not ServoErrors, mode 1 ServoEn and not ServoErrors.
    """

    def __init__(self, axis, plan, cycle_us, rng, ready_mode=0):
        self.axis = axis
        self.ready_mode = ready_mode
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
        self.last_ssp = 0  # outputs of the last frame that reached the drive
        self.missed = 0  # consecutive cycles whose frame did not reach the drive
        # misbehaviour, set by injections only (--inject)
        self.busy = False  # under an injection: the planned fault waits
        self.slow = {}  # timer name -> cycles: the next such answer comes that late
        self.slow_started = {}  # timer name -> cycle in which the slow answer was asked for
        self.overlay = {}  # "sew" / "ssw" bits ORed in, "rdy" inverts ServoRDY, "msg" code
        self.mute_ecat_timeout = False  # does not raise ECatTErr when frames stop coming
        self.clear_ack_cycle = None
        # --incident: why the drive last faulted (a cause id), a climbing motor temperature
        # (degrees per cycle, trip) and the cooling after it tripped
        self.cycle_s = cycle_us * 1e-6
        self.cause_id = None
        self.heating = None
        self.cooling = False

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
        if self.slow and name in self.slow:
            delay = self.slow.pop(name)
            self.slow_started[name] = self.k
        self.timers[name] = self.k + delay

    def step(self, k, ssp, scw, received=True):
        """Inputs (ActPos, SSW, SEW, code, data, extra 1..4) of cycle k.

        received False: the cycle's frame was lost before the drive, which keeps its last
        outputs and, at the third such cycle in a row, raises ECatTErr (E15).
        """
        self.k = k
        if received:
            self.last_ssp = ssp
            self.missed = 0
        else:
            ssp, scw = self.last_ssp, self.scw
            self.missed += 1
            if self.missed == 3 and not self.mute_ecat_timeout:
                self.fault(SEW_ECAT_TIMEOUT, "communication-loss")
        if self.timers:
            self._fire_timers()
        if self.heating or self.cooling:
            self._temperature_chain()
        if scw != self.scw:
            self._on_scw_change(self.scw, scw)
            self.scw = scw
        prev_speed = self.speed
        self._move(ssp, scw)
        return self._inputs(k, ssp, self.speed - prev_speed)

    # --- reactions ---
    def _fire_timers(self):
        for name, due in list(self.timers.items()):
            if due <= self.k and not (self.busy and name == "fault"):
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
        if not self.incremental:
            return  # an absolute encoder has no zero pulse to search
        if on:
            self._after("zpulse", 5, 20)
        else:
            self.timers.pop("zpulse", None)
            if self.zpulse_ack:
                self._after("zpulse_ack_off", 2, 5)

    def _on_error_clear(self, on):
        if on:  # with no error pending the drive clears nothing and acknowledges all the same
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
        self.clear_ack_cycle = self.k

    def _timer_err_clear_ack_off(self):
        self.err_clear_ack = False

    def _timer_table(self):
        scw = self.scw
        self.table = ((scw >> SCW_PRMTBL_SHIFT) & 3) | (((scw >> SCW_EXT_PRMTBL_SHIFT) & 1) << 2)

    def _timer_fault(self):
        self.fault(SEW_FOLLOWING, "following-error")  # the set point is steady then

    def _temperature_chain(self):
        """--incident overtemperature: the motor heats until it trips I2t_Endat, then cools."""
        if self.heating:
            per_cycle, trip = self.heating
            self.temp += per_cycle
            if self.temp >= trip:
                self.heating = None
                self.cooling = True
                self.fault(SEW_I2T_ENDAT, "overtemperature")
            return
        self.temp += (AMBIENT_C - self.temp) * min(1.0, self.cycle_s / COOLING_S)
        self.cooling = self.temp > AMBIENT_C + 1

    def fault(self, causes, cause_id=None):
        """A drive fault: summary and cause bits together, ServoRDY drops at once (mode 0),
        the power stage a few cycles later.  cause_id: the incident cause it must get."""
        if not self.sew & SEW_SERVO_ERRORS:
            self.cause_id = cause_id
        self.sew |= causes | SEW_SERVO_ERRORS
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
        ready = not self.sew and (self.en or self.ready_mode == 0)
        return ((SSW_SERVO_EN | SSW_PULSE_ENABLED if self.en else 0)
                | (SSW_SERVO_RDY if ready else 0)
                | (SSW_INCREMENTAL if self.incremental else 0)
                | (SSW_ZPULSE_ACK if self.zpulse_ack else 0)
                | (SSW_ERR_CLEAR_ACK if self.err_clear_ack else 0)
                | (SSW_N_ZERO if abs(speed) < N_ZERO_LIMIT else 0)
                | (SSW_N_SETPOINT if in_tolerance else 0)
                | (SSW_TEMP_WARNING if self.temp > TEMP_WARNING_C else 0)
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
        ssw, sew = self._ssw(ssp), self.sew
        if self.overlay:
            ssw, sew, code = self._overlaid(ssw, sew, code)
        return (self._actpos(), ssw, sew, code, data,
                following, torque, current, self.temp + 6.5)

    def _overlaid(self, ssw, sew, code):
        overlay = self.overlay
        ssw |= overlay.get("ssw", 0)
        if overlay.get("rdy"):
            ssw ^= SSW_SERVO_RDY
        return ssw, sew | overlay.get("sew", 0), overlay.get("msg", code)


# --- injected violations (--inject) and the findings they must produce (--findings) ---
MASTER, RETURNED = 0, 1  # a frame's place in its cycle: key = 2 * cycle + copy
DROP, LOST = "drop", "lost"  # a cycle missing from the capture / lost before the drives

# rule -> (timeout a timed finding waits for, or None: reported on the frame showing it;
#          default start as a fraction of the session; default axis, None for a bus rule).
# The defaults spread the injections so that all of them fit in one 2-second session.
INJECTABLE = {
    "COM-001": (None, 0.10, None),
    "SE-004": ("enable_response", 0.12, 0),
    "ZP-001": ("drive_response", 0.12, 1),
    "FLT-001": ("fault_reaction", 0.12, 2),
    "EC-004": ("clear_response", 0.12, 3),
    "COM-002": (None, 0.26, None),
    "ZP-003": (None, 0.28, 0),
    "SE-002": (None, 0.28, 1),
    "SE-003": ("drive_response", 0.28, 2),
    "SE-001": (None, 0.28, 3),
    "COM-004": (None, 0.33, None),
    "PT-001": ("param_table", 0.40, 0),
    "ZP-002": (None, 0.40, 1),
    "EC-002": ("nc_release", 0.40, 2),
    "EC-001": (None, 0.40, 3),
    "COM-003": ("drive_response", 0.50, 2),  # the axis is the drive that does not report
    "MSG-001": (None, 0.60, 0),
    "SEW-001": (None, 0.60, 1),
    "SCW-001": (None, 0.60, 2),
    "EC-003": ("drive_response", 0.60, 3),
    "COM-005": (None, 0.68, None),
    "SEW-003": (None, 0.72, 0),
    "SSW-001": (None, 0.72, 1),
    "RDY-001": ("drive_response", 0.72, 2),
    "SEW-002": ("drive_response", 0.72, 3),
    # what the drives and ESCs say themselves (acyclic frames; the axis picks the drive's slave)
    "ERH-001": (None, 0.25, 2),
    "MBX-003": (None, 0.30, 0),
    "LNK-001": (None, 0.35, 1),
    "DC-001": (None, 0.40, 1),
    "LNK-002": (None, 0.50, -1),  # the last slave: the end of the line
    # a drive's own words against its SEW (axis injections with mailbox traffic)
    "ERH-002": (None, 0.20, 1),
    "MBX-001": ("drive_response", 0.45, 1),
    "MBX-002": ("drive_response", 0.55, 0),
}
BUS_RULES = frozenset(("COM-001", "COM-002", "COM-003", "COM-004", "COM-005"))
# Shown by the master's acyclic frames between the cycles (PROTOCOL.md §11), not by the process
# data: they run whatever the axes do.  Their findings have axis null: without a start-up the
# validator does not know which station an axis is.
ACYCLIC_RULES = frozenset(("MBX-003", "ERH-001", "LNK-001", "LNK-002", "DC-001"))
# Judged on the axis whose drive said it (its emergencies, its 1003h against its SEW): the
# validator must know the axis's station, which --layout-config then names.
STATION_RULES = frozenset(("MBX-001", "MBX-002", "ERH-002"))
# What a capture with only one copy of each frame can show (inputs and WKC live in the
# returned copy; "not returned" needs the master copy).
NEEDS_BOTH_COPIES = frozenset(("COM-003", "COM-004", "COM-005"))
MASTER_ONLY_OK = frozenset(("SE-001", "SCW-001", "COM-002"))
# Other rules an injection necessarily fires as well.  COM-003 and COM-005 lose frames on the
# ring (master copy in the capture, no returned copy): each such master frame has no returned
# copy before the next cycle's, which is COM-004 (one per lost frame, axis null).  No other
# injection needs one: COM-002 drops only two cycles (no COM-003, which needs 3, nor COM-005,
# which needs more than 3), COM-003 loses exactly 3 (not more than the limit: no COM-005), the
# momentary drive faults (SE-002, ZP-002, EC-001) end within drive_response / 4 so SE-003,
# ZP-001 and EC-003 do not follow, and FLT-001's NC keeps SE 2 until the drive is off (no SE-003).
COMPANIONS = {
    "COM-003": ["COM-004"],
    "COM-005": ["COM-004"],
}
SLACK_CYCLES = 2  # a timed finding's window ends this many cycles after the frame it is due on
# ... and starts this many before it: the validator may time the condition from the other copy of
# its first cycle (docs/timing.md#rule-time), never from an earlier cycle.
EARLY_CYCLES = 1
FIRST_INJECTION_CYCLE = 10  # after the 8 intervals COM-002 needs to know the cycle time


# --incident KIND[@SECONDS][:AXIS]: a drive fault with the chain of evidence its cause needs
# (INTERFACES.md "Incidents"), run like an injection (an axis's or, for a bus chain, alone).
# kind -> (default start as a fraction of the session, default axis).  The session's own planned
# fault (axis 1, a following error at a steady set point) is an incident too.
CHAINS = {
    "communication-loss": (0.20, 2),
    "link-fault": (0.57, 2),
    "overtemperature": (0.30, 3),
    "following-error-after-step": (0.40, 0),
    "bus-outage": (0.65, None),
}
BUS_CHAINS = frozenset(("communication-loss", "link-fault", "bus-outage"))
OUTAGE_CYCLES = 8  # the bus outage: frames lost before the drives
TELEGRAM_FAILURE_LIMIT = 3  # COM-005's default: an outage is every axis failing longer
STEP_UNITS = 200_000  # the set-point step: 2000 rpm in one cycle
HEATING_C_PER_S, TRIP_C = 200.0, 96.0  # the overtemperature chain's climb and I2t_Endat trip
FOLLOWING_AFTER_STEP_NS = 25_000_000  # FollowerErr this long after the step


def parse_chain(text, order, args, error):
    """KIND[@SECONDS][:AXIS] -> Injection running that chain."""
    kind, _, axis_text = text.partition(":")
    kind, _, time_text = kind.partition("@")
    kind = kind.strip().lower()
    if kind not in CHAINS:
        error(f"--incident {text}: no chain {kind!r}; one of {', '.join(sorted(CHAINS))}")
    fraction, default_axis = CHAINS[kind]
    cycle_s = args.cycle_us * 1e-6
    try:
        seconds = float(time_text) if time_text else fraction * args.cycles * cycle_s
        axis = int(axis_text) if axis_text else default_axis
        if axis is not None:
            axis %= args.axes
    except ValueError:
        error(f"--incident {text}: expected KIND[@SECONDS][:AXIS], e.g. overtemperature@0.6:3")
    start_cycle = max(FIRST_INJECTION_CYCLE, math.ceil(seconds / cycle_s - 1e-9))
    if not 0 <= seconds or start_cycle >= args.cycles:
        error(f"--incident {text}: {seconds} s is outside the capture "
              f"({args.cycles * cycle_s:g} s)")
    if (axis is None) != (kind == "bus-outage"):
        error(f"--incident {text}: the bus outage has no axis, every other chain one")
    if axis is not None and not 0 <= axis < args.axes:
        error(f"--incident {text}: axis {axis} does not exist (--axes {args.axes})")
    chain = Injection(kind, axis, start_cycle, order)
    chain.bus = kind in BUS_CHAINS
    return chain


class Injection:
    """One --inject request: RULE[@SECONDS][:AXIS]."""

    def __init__(self, rule, axis, start_cycle, order):
        self.rule, self.axis, self.start_cycle, self.order = rule, axis, start_cycle, order
        self.bus = rule in BUS_RULES
        self.acyclic = rule in ACYCLIC_RULES

    def __str__(self):
        return self.rule if self.axis is None else f"{self.rule}:{self.axis}"


def parse_injection(text, order, args, error):
    """RULE[@SECONDS][:AXIS] -> Injection, with the rule's default time and axis."""
    rule, _, axis_text = text.partition(":")
    rule, _, time_text = rule.partition("@")
    rule = rule.strip().upper()
    if rule not in INJECTABLE:
        error(f"--inject {text}: cannot inject {rule!r}; one of {', '.join(sorted(INJECTABLE))}")
    _, fraction, default_axis = INJECTABLE[rule]
    cycle_s = args.cycle_us * 1e-6
    try:
        seconds = float(time_text) if time_text else fraction * args.cycles * cycle_s
        axis = int(axis_text) if axis_text else None
    except ValueError:
        error(f"--inject {text}: expected RULE[@SECONDS][:AXIS], e.g. SE-001@0.5:2")
    start_cycle = max(FIRST_INJECTION_CYCLE, math.ceil(seconds / cycle_s - 1e-9))
    if not 0 <= seconds or start_cycle >= args.cycles:
        error(f"--inject {text}: {seconds} s is outside the capture "
              f"({args.cycles * cycle_s:g} s)")
    if rule == "ZP-001" and args.axes == 1:
        error(f"--inject {text}: ZP-001 needs an incremental axis (odd index): use --axes 2 or more")
    if axis is None and (rule not in BUS_RULES or rule == "COM-003"):
        axis = default_axis % args.axes
        if rule == "ZP-001" and axis % 2 == 0:
            axis = axis + 1 if axis + 1 < args.axes else 1
        if rule == "ZP-003" and axis % 2:
            axis -= 1
    if axis is not None:
        if rule in BUS_RULES and rule != "COM-003":
            error(f"--inject {text}: {rule} concerns the whole frame, it takes no axis")
        if not 0 <= axis < args.axes:
            error(f"--inject {text}: axis {axis} does not exist (--axes {args.axes})")
        if rule == "ZP-001" and axis % 2 == 0:
            error(f"--inject {text}: ZP-001 needs an incremental axis (odd index)")
        if rule == "ZP-003" and axis % 2:
            error(f"--inject {text}: ZP-003 needs an absolute axis (even index)")
    if args.copies != "both" and rule in NEEDS_BOTH_COPIES:
        error(f"--inject {text}: {rule} needs both copies of each frame (--copies both)")
    if args.copies == "master" and rule not in MASTER_ONLY_OK:
        error(f"--inject {text}: a capture of master copies cannot show {rule}")
    return Injection(rule, axis, start_cycle, order)


class Expectations:
    """The findings the injections must produce, resolved to frame windows at the end."""

    def __init__(self, cycle_ns, delay_ns):
        self.cycle_ns, self.delay_ns = cycle_ns, delay_ns
        self.items = []
        self.exact = []  # (rule, axis, index of the frame)
        self.times, self.keys = [], []  # every written frame, in order
        self.records = None  # each frame's record number, when other records come between

    def add(self, rule, axis, cycle, copy, timeout=None, ref=None, end=None, due=None):
        """The condition shows first in (cycle, copy); a timed one is due `timeout` after
        the time of `ref` (a key; default the same place); `end` closes an explicit window
        in which the finding is due at `due` (keys)."""
        self.items.append((rule, axis, 2 * cycle + copy, timeout, ref, end, due))

    def add_last_frame(self, rule, axis):
        """Shown by the frame written last: reported exactly there."""
        self.exact.append((rule, axis, len(self.times) - 1))

    def frame(self, t_ns, cycle, copy):
        self.times.append(t_ns)
        self.keys.append(2 * cycle + copy)

    def _key_time(self, key):
        """Capture time of a place in a cycle, whether or not a frame was written there."""
        cycle, copy = divmod(key, 2)
        return T0_NS + cycle * self.cycle_ns + copy * self.delay_ns

    def _first_at(self, key, rule):
        """Index of the first frame at or after key that can show it (inputs: returned)."""
        i = bisect.bisect_left(self.keys, key)
        while i < len(self.keys) and key % 2 and self.keys[i] % 2 == 0:
            i += 1
        if i == len(self.keys):
            raise ValueError(f"{rule}: the capture ends before the injected condition shows")
        return i

    def _number(self, index):
        return self.records[index] if self.records is not None else index + 1

    def resolve(self):
        expected = []
        for rule, axis, key, timeout, ref, end, due_key in self.items:
            first = self._first_at(key, rule)
            due = first
            if end is not None:
                last = self._first_at(end, rule)
                due = first if due_key is None else self._first_at(due_key, rule)
            elif timeout is None:
                last = first
            else:
                limit = self._key_time(key if ref is None else ref) + TIMEOUT_MS[timeout] * 10**6
                due = bisect.bisect_right(self.times, limit)
                if due == len(self.times):
                    raise ValueError(f"{rule}: the capture ends before {timeout} has passed")
                slack = self.times[due] + SLACK_CYCLES * self.cycle_ns
                last = bisect.bisect_right(self.times, slack) - 1
                early = self.times[due] - EARLY_CYCLES * self.cycle_ns
                first = max(first, bisect.bisect_left(self.times, early))
            expected.append({"rule": rule, "axis": axis, "first_frame": self._number(first),
                             "last_frame": self._number(last), "due_frame": self._number(due)})
        for rule, axis, index in self.exact:
            number = self._number(index)
            expected.append({"rule": rule, "axis": axis, "first_frame": number,
                             "last_frame": number, "due_frame": number})
        expected.sort(key=lambda e: (e["first_frame"], e["rule"], -1 if e["axis"] is None
                                     else e["axis"]))
        return expected


class Injector:
    """The script of one injection, stepped once per cycle (each yield is one cycle).

    An axis injection runs on top of its NC's script stack, so it sees the drive only through
    the returned copies, like the NC, and also steers the drive's misbehaviour directly.  A bus
    injection is stepped by the session before the NCs and says what happens to the frame.
    Every script starts from an enabled, idle axis and ends there again.
    """

    def __init__(self, inj, session):
        self.inj = inj
        self.session = session
        self.cycle_ns = session.cycle_ns
        self.rng = random.Random(f"{session.seed}/inject/{inj.order}")
        if not inj.bus:
            self.nc, self.drive = session.ncs[inj.axis], session.drives[inj.axis]
        self.saved_target = 0

    # --- helpers ---
    def k(self):
        return self.session.k

    def t(self):
        """Capture time of this cycle's master copy, ns after the first frame."""
        return self.session.k * self.cycle_ns

    def timeout_ns(self, name):
        return TIMEOUT_MS[name] * 10**6

    def cycles_over(self, ns):
        """Fewest cycles that last at least ns."""
        return max(1, -(-ns // self.cycle_ns))

    def short_cycles(self):
        """A momentary condition: at most a quarter of drive_response, at least one cycle."""
        return max(1, self.timeout_ns("drive_response") // 4 // self.cycle_ns)

    def expect(self, cycle, copy, timeout=None, **kw):
        inj = self.inj
        assert timeout == INJECTABLE[inj.rule][0], (inj.rule, timeout)
        if self.session.expect is not None:  # --findings asked for the windows
            self.session.expect.add(inj.rule, inj.axis, cycle, copy, timeout, **kw)

    def expect_now(self, copy, timeout=None):
        self.expect(self.k(), copy, timeout)

    def hold(self, cycles):
        for _ in range(cycles):
            yield

    def until(self, condition):
        while not condition():
            yield

    def wait_ns(self, t_ns):
        while self.t() < t_ns:
            yield

    # --- axis scripts ---
    def run_axis(self):
        nc, drive = self.nc, self.drive
        nc.injection, drive.busy = self, True
        yield from getattr(self, "_" + self.inj.rule.replace("-", "_").lower())()
        yield from self.until(nc.settled)
        nc.injection, drive.busy = None, False

    def _disable(self):
        """A legal disable, set point to zero; returns once the drive is off."""
        nc = self.nc
        self.saved_target = nc.target
        nc.target = nc.ssp = 0
        nc.se = 0
        self.off_ns = self.t()
        yield from self.until(lambda: not nc.ssw & SSW_SERVO_EN)
        yield from self.hold(self.rng.randint(2, 5))

    def _enable(self, slow_ns=None):
        """A legal enable (SE 0x1 then 0x2); the motion resumes once the drive is on."""
        nc = self.nc
        nc.se = 1
        yield from self.hold(self.rng.randint(1, 3))
        if slow_ns:
            self.drive.slow["enable"] = self.cycles_over(slow_ns)
        nc.se = 2
        if slow_ns:
            self.expect_now(MASTER, "enable_response")
        yield from self.until(lambda: nc.ssw & SSW_SERVO_EN)
        nc.target = self.saved_target

    def _se_001(self):
        yield from self._disable()
        self.nc.se = 2  # from 0x0: not an enable; the drive rightly stays off
        self.expect_now(MASTER)
        yield from self.wait_ns(self.t() + 2 * self.timeout_ns("drive_response"))
        yield from self._enable()  # 0x2 -> 0x1 -> 0x2

    def _se_002(self):
        yield from self._disable()
        yield from self.wait_ns(self.off_ns + 2 * self.timeout_ns("drive_response"))
        self.drive.en = True
        self.expect_now(RETURNED)
        yield from self.hold(self.short_cycles())
        self.drive.en = False
        yield from self.until(lambda: not self.nc.ssw & SSW_SERVO_EN)
        yield from self.hold(self.rng.randint(2, 5))
        yield from self._enable()

    def _se_003(self):
        nc = self.nc
        self.drive.slow["disable"] = self.cycles_over(2 * self.timeout_ns("drive_response"))
        self.saved_target = nc.target
        nc.target = nc.ssp = 0
        nc.se = 0
        self.expect_now(MASTER, "drive_response")
        yield from self.until(lambda: not nc.ssw & SSW_SERVO_EN)
        yield from self.hold(self.rng.randint(2, 5))
        yield from self._enable()

    def _se_004(self):
        yield from self._disable()
        yield from self._enable(slow_ns=2 * self.timeout_ns("enable_response"))

    def _zp_001(self):
        nc = self.nc
        self.drive.slow["zpulse_ack_off"] = self.cycles_over(2 * self.timeout_ns("drive_response"))
        nc.zpulse_request = True
        yield from self.until(lambda: nc.ssw & SSW_ZPULSE_ACK)
        nc.zpulse_request = False
        self.expect_now(MASTER, "drive_response")
        yield from self.until(lambda: not nc.ssw & SSW_ZPULSE_ACK)

    def _momentary(self, attribute, bit):
        """The drive raises a handshake bit on its own, after the NC's request bit has been 0
        for 2 x drive_response, and drops it again before drive_response."""
        yield from self.wait_ns(self.t() + 2 * self.timeout_ns("drive_response"))
        setattr(self.drive, attribute, True)
        self.expect_now(RETURNED)
        yield from self.hold(self.short_cycles())
        setattr(self.drive, attribute, False)
        yield from self.until(lambda: not self.nc.ssw & bit)

    def _zp_002(self):
        yield from self._momentary("zpulse_ack", SSW_ZPULSE_ACK)

    def _zp_003(self):
        nc = self.nc
        nc.zpulse_request = True  # on an absolute axis: the drive ignores it
        self.expect_now(MASTER)
        yield from self.wait_ns(self.t() + 2 * self.timeout_ns("drive_response"))
        nc.zpulse_request = False

    def _ec_001(self):
        yield from self._momentary("err_clear_ack", SSW_ERR_CLEAR_ACK)

    def _ec_002(self):
        nc = self.nc
        nc.error_clear = True
        yield from self.until(lambda: nc.ssw & SSW_ERR_CLEAR_ACK)
        ack = self.drive.clear_ack_cycle
        self.expect(ack, RETURNED, "nc_release")
        yield from self.wait_ns(ack * self.cycle_ns + 2 * self.timeout_ns("nc_release"))
        nc.error_clear = False
        yield from self.until(lambda: not nc.ssw & SSW_ERR_CLEAR_ACK)

    def _ec_003(self):
        nc = self.nc
        self.drive.slow["err_clear_ack_off"] = \
            self.cycles_over(2 * self.timeout_ns("drive_response"))
        nc.error_clear = True
        yield from self.until(lambda: nc.ssw & SSW_ERR_CLEAR_ACK)
        nc.error_clear = False
        self.expect_now(MASTER, "drive_response")
        yield from self.until(lambda: not nc.ssw & SSW_ERR_CLEAR_ACK)

    def _fault(self, causes, slow_timer, slow_ns):
        """A drive fault the NC recovers from with its own script (pushed on top of this one
        when it sees ServoErrors); this script resumes once the recovery is over."""
        self.drive.slow[slow_timer] = self.cycles_over(slow_ns)
        self.drive.fault(causes)
        yield
        yield from self.until(lambda: not self.nc.recovering)

    def _ec_004(self):
        yield from self._fault(SEW_OVERLOAD, "clear", 2 * self.timeout_ns("clear_response"))
        self.expect(self.drive.slow_started["clear"], MASTER, "clear_response")

    def _flt_001(self):
        self.nc.recover_waits_for_disable = True
        self.expect_now(RETURNED, "fault_reaction")
        yield from self._fault(SEW_PDPINT, "disable", 2 * self.timeout_ns("fault_reaction"))
        self.nc.recover_waits_for_disable = False

    def _sew_002(self):
        self.expect_now(RETURNED, "drive_response")
        # summary bit only; the ErrorClear that ends it is answered 2 x drive_response late
        yield from self._fault(0, "clear", 2 * self.timeout_ns("drive_response"))

    def _overlay(self, key, value, timeout=None):
        self.drive.overlay[key] = value
        self.expect_now(RETURNED, timeout)
        yield from self.wait_ns(self.t() + 2 * self.timeout_ns("drive_response"))
        del self.drive.overlay[key]

    def _sew_001(self):
        yield from self._overlay("sew", SEW_I2T_ENDAT)

    def _sew_003(self):
        yield from self._overlay("sew", SEW_RESERVED_BIT4)

    def _ssw_001(self):
        yield from self._overlay("ssw", 1 << 13)

    def _rdy_001(self):
        yield from self._overlay("rdy", True, "drive_response")

    def _msg_001(self):
        yield from self._overlay("msg", 7)

    def _scw_001(self):
        self.nc.extra_scw = 1 << 16
        self.expect_now(MASTER)
        yield from self.wait_ns(self.t() + 2 * self.timeout_ns("drive_response"))
        self.nc.extra_scw = 0

    def _pt_001(self):
        nc = self.nc
        table = nc.table
        self.drive.slow["table"] = self.cycles_over(2 * self.timeout_ns("param_table"))
        nc.table = table ^ 1
        self.expect_now(MASTER, "param_table")
        yield from self.until(lambda: nc.active_table() == nc.table)
        nc.table = table  # back, followed in time
        yield from self.until(lambda: nc.active_table() == nc.table)

    # --- a drive's own words against its SEW (STATION_RULES; PROTOCOL.md section 11) ---
    def _send(self, script):
        """An acyclic script's frames, each step's after its cycle's frame."""
        for frames in script:
            self.session.acyclic.queue += frames or []
            yield

    def _mailbox_found(self):
        """The NC reads 1003h:00: the validator finds the drive's mailbox areas from use."""
        acyclic = self.session.acyclic
        mailbox = acyclic.mailbox(self.inj.axis)
        yield from self._send(acyclic._upload_count(mailbox, self.inj.axis))
        return mailbox

    def _mbx_001(self):
        """The drive sends an emergency (0x8611 following error) while its SEW shows nothing,
        then nothing for 2 x drive_response; from then on it reports each fault with one."""
        mailbox = yield from self._mailbox_found()
        self.session.acyclic.queue.append(mailbox.emergency(0x8611, 0x21))
        self.session.acyclic.reporting.add(self.inj.axis)
        self.expect_now(RETURNED, "drive_response")
        yield
        yield from self.wait_ns(self.t() + 2 * self.timeout_ns("drive_response"))

    def _mbx_002(self):
        """A drive that reports each fault with an emergency (after the cycle that shows the
        cause bit): a following error reported so; after the NC's recovery, a second one with
        none; later faults reported again."""
        nc, acyclic = self.nc, self.session.acyclic
        yield from self._mailbox_found()
        acyclic.reporting.add(self.inj.axis)
        recoveries = nc.recoveries
        self.drive.fault(SEW_FOLLOWING)
        yield
        yield from self._until_fault_recovered(nc, recoveries)
        yield from self.until(nc.settled)
        recoveries = nc.recoveries
        acyclic.silent.add(self.inj.axis)
        self.drive.fault(SEW_FOLLOWING)
        self.expect_now(RETURNED, "drive_response")
        yield
        yield from self._until_fault_recovered(nc, recoveries)

    def _erh_002(self):
        """A following error (0x8611 in section 7); the NC reads 1003h:01, and the drive's
        newest entry carries 0x2300 (current), error number 2, class 0x03."""
        nc, acyclic = self.nc, self.session.acyclic
        mailbox = acyclic.mailbox(self.inj.axis)
        recoveries = nc.recoveries
        self.drive.fault(SEW_FOLLOWING)
        yield
        entry = 2 << 24 | 0x03 << 16 | CANOPEN_CODE[SEW_OVERLOAD]
        yield from self._send(acyclic._sdo(
            mailbox, (SDO_UPLOAD, ERROR_FIELD, 1),
            (COE_SDO_RESPONSE, SDO_UPLOADED | SDO_EXPEDITED | SDO_SIZE_INDICATED, ERROR_FIELD, 1,
             entry), [(self.inj.rule, self.inj.axis)]))
        yield from self._until_fault_recovered(nc, recoveries)

    # --- incident chains (--incident) ---
    def _until_fault_recovered(self, nc, recoveries):
        """The drive's fault reaches the NC, which clears it and enables the axis again (its
        recovery runs on top of an axis chain, which resumes after it)."""
        yield from self.until(lambda: nc.recoveries > recoveries)

    def _communication_loss(self):
        """2 cycles lost before the drives (under the telegram failure limit: no ECatTErr),
        then the axis's drive raises ECatWatchDog 3 cycles after."""
        axis = self.inj.axis
        recoveries = self.session.ncs[axis].recoveries
        yield from self._outage(LOST, 2)
        yield from self.hold(3)
        self.session.drives[axis].fault(SEW_ECAT_WATCHDOG, "communication-loss")
        yield from self._until_fault_recovered(self.session.ncs[axis], recoveries)

    def _link_fault(self):
        """The counters polled (two polls: the baseline, then one unchanged), 2 cycles lost
        before the drives, the axis's drive raising ECatWatchDog 3 cycles after; the link into
        the drive's port 0 counts the RX errors, shown at the next poll (PROTOCOL.md §11)."""
        axis = self.inj.axis
        acyclic = self.session.acyclic
        acyclic.counters.start(self.k())
        polls = acyclic.counters.polls + 2
        yield from self.until(lambda: acyclic.counters.polls >= polls)
        recoveries = self.session.ncs[axis].recoveries
        yield from self._outage(LOST, 2)
        yield from self.hold(3)
        self.session.drives[axis].fault(SEW_ECAT_WATCHDOG, "link-fault")
        acyclic.counters.rise(acyclic.first_servo + axis, RX_ERROR, RX_ERRORS, "LNK-001")
        yield from self._until_fault_recovered(self.session.ncs[axis], recoveries)

    def _bus_outage(self):
        """OUTAGE_CYCLES cycles lost before the drives: every axis fails longer than the
        telegram failure limit (the master copy after the limit's cycle shows it), and every
        drive raises ECatTErr at its third missed cycle."""
        ncs = self.session.ncs
        recoveries = [nc.recoveries for nc in ncs]
        self.session.outage_cycles.add(self.k() + TELEGRAM_FAILURE_LIMIT + 1)
        yield from self._outage(LOST, OUTAGE_CYCLES)
        yield from self.until(lambda: all(nc.recoveries > r for nc, r in zip(ncs, recoveries)))

    def _overtemperature(self):
        """The motor temperature climbs HEATING_C_PER_S (message code 4; SSW.TempWarning over
        80 °C) until the drive trips I2t_Endat at TRIP_C."""
        recoveries = self.nc.recoveries
        self.drive.heating = (HEATING_C_PER_S * self.cycle_ns * 1e-9, TRIP_C)
        yield from self._until_fault_recovered(self.nc, recoveries)

    def _following_error_after_step(self):
        """The NC steps the speed set point by STEP_UNITS in one cycle; the drive raises
        FollowerErr FOLLOWING_AFTER_STEP_NS later."""
        nc = self.nc
        recoveries = nc.recoveries
        step = STEP_UNITS if nc.ssp >= 0 else -STEP_UNITS
        nc.target = nc.ssp = nc.ssp + step
        yield from self.hold(self.cycles_over(FOLLOWING_AFTER_STEP_NS))
        self.drive.fault(SEW_FOLLOWING, "following-error-after-step")
        yield from self._until_fault_recovered(nc, recoveries)

    # --- bus scripts ---
    def run_bus(self):
        session = self.session
        for drive in session.drives:
            drive.busy = True
        yield from getattr(self, "_" + self.inj.rule.replace("-", "_").lower())()
        yield from self.until(lambda: all(nc.settled() for nc in session.ncs))
        for drive in session.drives:
            drive.busy = False

    def _outage(self, what, cycles):
        for _ in range(cycles):
            self.session.directive = what
            yield
        self.session.directive = None

    def _com_001(self):
        self.session.wkc = 3 * len(self.session.ncs) - 1
        self.expect_now(RETURNED)
        yield
        self.session.wkc = None

    def _com_002(self):
        k0 = self.k()
        yield from self._outage(DROP, 2)
        # Told lost by the interval after the gap: on the next master frame (docs/rules.md#com-002).
        self.expect(k0 + 3, MASTER)

    def _com_004(self):
        k0 = self.k()
        yield from self._outage(LOST, 1)
        self.expect(k0 + 1, MASTER)

    def _com_003(self):
        k0 = self.k()
        drive = self.session.drives[self.inj.axis]
        drive.mute_ecat_timeout = True
        yield from self._outage(LOST, 3)
        self.expect(k0 + 3, MASTER, "drive_response", ref=2 * (k0 + 3) + RETURNED)
        yield from self.wait_ns((k0 + 3) * self.cycle_ns + 2 * self.timeout_ns("drive_response"))
        drive.mute_ecat_timeout = False

    def _com_005(self):
        k0 = self.k()
        yield from self._outage(LOST, 4)
        for axis in range(len(self.session.ncs)):  # every axis lost its frames
            self.session.expect.add("COM-005", axis, k0 + 3, MASTER,
                                    end=2 * (k0 + 4) + RETURNED, due=2 * (k0 + 4) + MASTER)


class Monitor:
    """--self-check: every axis not under an injection conforms, cycle by cycle.

    Static checks on each cycle's values, and every "longer than T" condition of docs/rules.md
    measured on the cycle's time (the NC's outputs and the inputs it gets back).
    """

    # name, timeout, condition on (scw, ssw, sew, valid enable)
    TIMED = (
        ("ServoEn without a valid enable (SE-003)", "drive_response",
         lambda scw, ssw, sew, valid: ssw & SSW_SERVO_EN and not valid),
        ("ZPulseAck without ZPulseRequest (ZP-001)", "drive_response",
         lambda scw, ssw, sew, valid: ssw & SSW_ZPULSE_ACK and not scw & SCW_ZPULSE_REQUEST),
        ("ErrClearAck without ErrorClear (EC-003)", "drive_response",
         lambda scw, ssw, sew, valid: ssw & SSW_ERR_CLEAR_ACK and not scw & SCW_ERROR_CLEAR),
        ("ErrorClear after ErrClearAck (EC-002)", "nc_release",
         lambda scw, ssw, sew, valid: ssw & SSW_ERR_CLEAR_ACK and scw & SCW_ERROR_CLEAR),
        ("ErrorClear not acknowledged (EC-004)", "clear_response",
         lambda scw, ssw, sew, valid: scw & SCW_ERROR_CLEAR and sew & SEW_SERVO_ERRORS
         and not ssw & SSW_ERR_CLEAR_ACK),
        ("summary bit without a cause (SEW-002)", "drive_response",
         lambda scw, ssw, sew, valid: sew & SEW_SERVO_ERRORS and not sew & SEW_CAUSES),
        ("enabled with an error (FLT-001)", "fault_reaction",
         lambda scw, ssw, sew, valid: ssw & SSW_SERVO_EN and sew & SEW_SERVO_ERRORS),
        ("enable not honoured (SE-004)", "enable_response",
         lambda scw, ssw, sew, valid: valid and not ssw & SSW_SERVO_EN and ssw & SSW_SERVO_RDY
         and not sew & SEW_SERVO_ERRORS and scw & SCW_EMGON and scw & SCW_BRAKE),
        ("parameter table not followed (PT-001)", "param_table",
         lambda scw, ssw, sew, valid:
         (((scw >> SCW_PRMTBL_SHIFT) & 3) | (((scw >> SCW_EXT_PRMTBL_SHIFT) & 1) << 2))
         != (((ssw >> SSW_PRMTBL_SHIFT) & 3) | (((ssw >> SSW_EXT_PRMTBL_SHIFT) & 1) << 2))),
    )

    def __init__(self, session, ready_mode):
        self.session = session
        self.ready_mode = ready_mode
        n = len(session.ncs)
        self.prev_se = [None] * n
        self.valid = [False] * n
        self.since = [[None] * len(self.TIMED) for _ in range(n)]

    def check(self, k, outputs, inputs):
        t = k * self.session.cycle_ns
        for axis, (out, inp) in enumerate(zip(outputs, inputs)):
            scw = out[1]
            ssw, sew, code = inp[1], inp[2], inp[3]
            se, prev = scw & SCW_SE, self.prev_se[axis]
            self.prev_se[axis] = se
            self.valid[axis] = se == 2 and (prev == 1 or (prev == 2 and self.valid[axis]))
            if self.session.ncs[axis].injection is not None:
                self.since[axis] = [None] * len(self.TIMED)
                continue
            problems = []
            if scw & SCW_RESERVED:
                problems.append("reserved SCW bits")
            if se == 2 and prev not in (None, 1, 2):
                problems.append(f"SE {prev} -> 2")
            if scw & SCW_ZPULSE_REQUEST and not ssw & SSW_INCREMENTAL:
                problems.append("ZPulseRequest on an absolute axis")
            if ssw & SSW_RESERVED or sew & SEW_RESERVED:
                problems.append("reserved SSW/SEW bits")
            if sew & SEW_CAUSES and not sew & SEW_SERVO_ERRORS:
                problems.append("SEW cause without the summary bit")
            if not 0 <= code <= 5:
                problems.append(f"message code {code}")
            error = bool(sew & SEW_SERVO_ERRORS)
            ready = not error and (self.ready_mode == 0 or ssw & SSW_SERVO_EN)
            if bool(ssw & SSW_SERVO_RDY) != ready:
                problems.append("ServoRDY against the Servo_Ready_Mode table")
            since = self.since[axis]
            for i, (name, timeout, condition) in enumerate(self.TIMED):
                if not condition(scw, ssw, sew, self.valid[axis]):
                    since[i] = None
                elif since[i] is None:
                    since[i] = t
                elif t - since[i] >= TIMEOUT_MS[timeout] * 10**6:
                    problems.append(f"{name} for {(t - since[i]) / 1e6:g} ms")
            if problems:
                raise SystemExit(f"gen_capture: self-check failed at cycle {k}, axis {axis}: "
                                 + "; ".join(problems))


# --- the master's acyclic frames (--inject of ACYCLIC_RULES; PROTOCOL.md §11) ---
COUNTER_POLL_NS = 50_000_000  # every slave's ESC error counters
DC_POLL_NS = 10_000_000  # every slave's system time difference
DC_IN_SYNC_NS = 80  # a synchronised slave's difference stays within this (well under 100)
DC_OUT_OF_SYNC_NS = (-5000, -5200, -4900)  # DC-001: these reads in a row (limit 1000 ns)
RX_ERRORS = 4  # LNK-001
PRELOGGED_ENTRIES = 3  # ERH-001: the 1003h entries its drive holds from before the capture
MAX_ENTRIES = 8
SDO_EMPTY_POLLS = 2  # reads of SM1 before the drive's answer is there (WKC 0)
ERH_READ_GAP_NS = 100_000_000  # ERH-001: between the NC's reads of 1003h:00
EXPEDITED_BYTE = SDO_EXPEDITED | SDO_SIZE_INDICATED | 3 << 2  # 1 byte used, 3 unused


def dc_difference(ns):
    """0x092C as a slave holds it: sign and magnitude, not two's complement."""
    return DC_SMALLER | -ns if ns < 0 else ns


def mailbox_message(counter, service, command, index, subindex, data):
    """A CoE SDO message (mailbox header: length, address, channel and priority, type and
    counter; CoE header: number 0, service), padded to the mailbox area."""
    sdo = struct.pack("<HBHBI", service << 12, command, index, subindex, data)
    header = struct.pack("<HHBB", len(sdo), 0, 0, MBX_COE | counter << 4)
    return (header + sdo).ljust(MBX_SIZE, b"\0")


class AcyclicFrame:
    """Datagrams (command, ADP, ADO, data sent, data returned, returned WKC; data may be a
    function of the time the frame is sent) and the findings (rule, axis) its returned copy
    must produce."""

    def __init__(self, datagrams, shows=()):
        self.datagrams = datagrams
        self.shows = list(shows)


class Mailbox:
    """A drive's mailbox as the master uses it (no start-up: the validator finds the areas from
    use): a request written into SM0, the answer read from SM1; each side counts its messages
    1..7.  An abort, either side's, is an SDO request (ETG.1000.6; SOES and the SSC send it so)."""

    def __init__(self, station):
        self.station = station
        self.sent = self.answered = 0

    def write(self, command, index, subindex, data=0):
        self.sent = self.sent % 7 + 1
        message = mailbox_message(self.sent, COE_SDO_REQUEST, command, index, subindex, data)
        return AcyclicFrame([(CMD_FPWR, self.station, MBX_OUT, message, message, 1)])

    def emergency(self, code, register, shows=()):
        """A read of SM1 holding the drive's CoE emergency: error code, error register (1001h),
        5 bytes of manufacturer data (PROTOCOL.md section 11)."""
        self.answered = self.answered % 7 + 1
        body = struct.pack("<HHB5s", COE_EMERGENCY << 12, code, register, bytes(5))
        header = struct.pack("<HHBB", len(body), 0, 0, MBX_COE | self.answered << 4)
        message = (header + body).ljust(MBX_SIZE, b"\0")
        empty = bytes(MBX_SIZE)
        return AcyclicFrame([(CMD_FPRD, self.station, MBX_IN, empty, message, 1)], shows)

    def read(self, answer=None, shows=()):
        """A read of SM1; without an answer (service, command, index, subindex, data) it is
        still empty and the read is not done (WKC 0)."""
        empty = bytes(MBX_SIZE)
        if answer is None:
            return AcyclicFrame([(CMD_FPRD, self.station, MBX_IN, empty, empty, 0)])
        self.answered = self.answered % 7 + 1
        message = mailbox_message(self.answered, *answer)
        return AcyclicFrame([(CMD_FPRD, self.station, MBX_IN, empty, message, 1)], shows)


class Poller:
    """FPRD of one register block of every slave, in ring order (frames of at most
    MAX_FRAME_DATAGRAMS bytes), every period from the first injection that needs it."""

    first_datagrams = ()  # put before the reads in the poll's first frame

    def __init__(self, slaves, register, size, period):
        self.slaves, self.register, self.size, self.period = slaves, register, size, period
        self.next_cycle = None
        self.polls = 0
        self.shows = []  # (slave, rule): the next poll's read of slave shows it

    def start(self, k):
        if self.next_cycle is None:
            self.next_cycle = k

    def step(self, k):
        if self.next_cycle is None or k < self.next_cycle:
            return []
        self.next_cycle = k + self.period
        self.polls += 1
        per_frame = (MAX_FRAME_DATAGRAMS - 16 * len(self.first_datagrams)) // (12 + self.size)
        frames = []
        for first in range(0, self.slaves, per_frame):
            slaves = range(first, min(first + per_frame, self.slaves))
            frames.append(AcyclicFrame(
                (list(self.first_datagrams) if first == 0 else [])
                + [(CMD_FPRD, FIRST_STATION + s, self.register, bytes(self.size), self.value(s),
                    1) for s in slaves],
                [(rule, None) for s, rule in self.shows if s in slaves]))
        self.shows = []
        return frames


class ErrorCounters(Poller):
    """0x0300-0x0313 of every slave: a few errors and lost links from before the capture at the
    ports in use (0 in, 1 out; the last slave's port 1 is the end of the line), else steady."""

    def __init__(self, slaves, period, rng):
        super().__init__(slaves, ERROR_COUNTERS, ERROR_COUNTERS_SIZE, period)
        self.values = []
        for s in range(slaves):
            counters = bytearray(ERROR_COUNTERS_SIZE)
            for port in (0, 1) if s + 1 < slaves else (0,):
                counters[INVALID_FRAME + 2 * port - ERROR_COUNTERS] = rng.randint(0, 2)
                counters[RX_ERROR + 2 * port - ERROR_COUNTERS] = rng.randint(0, 3)
                counters[FORWARDED + port - ERROR_COUNTERS] = rng.randint(0, 1)
                counters[LOST_LINK + port - ERROR_COUNTERS] = rng.randint(0, 2)
            self.values.append(counters)

    def rise(self, slave, register, count, rule):
        at = register - ERROR_COUNTERS
        self.values[slave][at] = min(0xFF, self.values[slave][at] + count)  # saturating
        self.shows.append((slave, rule))

    def value(self, slave):
        return bytes(self.values[slave])


def master_time(t_ns):
    """The master's clock in DC time (32 bits), which the reference clock follows."""
    return struct.pack("<I", (t_ns - DC_EPOCH_OFFSET_NS + DC_REFERENCE_OFF_NS) & 0xFFFFFFFF)


class DcDifferences(Poller):
    """0x092C of every slave: within DC_IN_SYNC_NS, or the values of an out-of-sync run.  The
    master writes its time into the reference clock (the first slave) before, as EtherLab
    does, so that the reference's difference means something too."""

    def __init__(self, slaves, period, rng):
        super().__init__(slaves, DC_DIFFERENCE, 4, period)
        self.rng = rng
        self.runs = {}  # slave -> the values it reads next
        self.first_datagrams = [(CMD_FPWR, FIRST_STATION, DC_ADO, master_time, master_time, 1)]

    def value(self, slave):
        run = self.runs.get(slave)
        if run:
            ns = run.pop(0)
            if not run:
                del self.runs[slave]
        else:
            ns = self.rng.randint(-DC_IN_SYNC_NS, DC_IN_SYNC_NS)
        return struct.pack("<I", dc_difference(ns))


class Acyclic:
    """The master's acyclic frames for the ACYCLIC_RULES injections: polls of every slave's
    error counters or DC difference, SDO transfers in a drive's mailbox.  Each injection is a
    script stepped once per cycle, yielding the frames to send after it; it starts at its time
    whatever the axes do, after the one before it on the same drive's mailbox (or, for the
    others, of the same rule on the same slave)."""

    def __init__(self, injections, session, first_servo, slaves):
        self.session = session
        self.first_servo = first_servo  # ring position of axis 0's drive
        self.pending = sorted(injections, key=lambda inj: (inj.start_cycle, inj.order))
        self.running = []  # (injection, script)
        self.taken = set()  # what a running script uses alone (_resource)
        self.k = 0
        rng = random.Random(f"{session.seed}/acyclic")
        self.counters = ErrorCounters(slaves, self._cycles(COUNTER_POLL_NS), rng)
        self.dc = DcDifferences(slaves, self._cycles(DC_POLL_NS), rng)
        self.mailboxes = {}
        # 1003h's entries per drive: one per SEW cause bit that rises (section 7), at most 8
        n = len(session.drives)
        self.entries = [PRELOGGED_ENTRIES if any(inj.rule == "ERH-001" and inj.axis == axis
                                                 for inj in injections) else 0
                        for axis in range(n)]
        self.sew = [0] * n
        self.queue = []  # frames an axis injection sends after this cycle's
        # drives that report each rise of a SEW cause bit with an emergency (MBX-001, MBX-002's),
        # and those whose next fault goes unreported (MBX-002)
        self.reporting, self.silent = set(), set()

    def observe(self, inputs):
        for axis, values in enumerate(inputs):
            rose = values[2] & ~self.sew[axis] & SEW_CAUSES
            self.sew[axis] = values[2]
            if rose:
                self.entries[axis] = min(MAX_ENTRIES, self.entries[axis] + bin(rose).count("1"))
            if rose and axis in self.reporting:
                if axis in self.silent:
                    self.silent.discard(axis)
                else:  # after the cycle that shows it
                    lowest = rose & -rose
                    self.queue.append(self.mailbox(axis).emergency(CANOPEN_CODE[lowest], 0x01))

    def _cycles(self, ns):
        """Fewest cycles that last at least ns."""
        return max(1, -(-ns // self.session.cycle_ns))

    @staticmethod
    def _resource(inj):
        """What the injection's script uses alone: a drive's mailbox, else its rule's rise or
        run on the axis's slave (two at once would show as one)."""
        return ("mailbox" if inj.rule in ("MBX-003", "ERH-001") else inj.rule, inj.axis)

    def step(self, k):
        """The frames to send after cycle k."""
        self.k = k
        waiting = set()
        for inj in list(self.pending):
            if inj.start_cycle > k:
                break
            resource = self._resource(inj)
            if resource in self.taken or resource in waiting:
                waiting.add(resource)  # after the one before it
                continue
            self.pending.remove(inj)
            self.taken.add(resource)
            script = getattr(self, "_" + inj.rule.replace("-", "_").lower())(inj)
            self.running.append((inj, self._releasing(resource, script)))
        frames = []
        for entry in list(self.running):
            try:
                frames += next(entry[1]) or []
            except StopIteration:
                self.running.remove(entry)
        frames += self.queue
        self.queue = []
        return frames + self.counters.step(k) + self.dc.step(k)

    def unfinished(self):
        return [str(inj) for inj in self.pending] + [str(inj) for inj, _ in self.running]

    def mailbox(self, axis):
        if axis not in self.mailboxes:
            self.mailboxes[axis] = Mailbox(FIRST_STATION + self.first_servo + axis)
        return self.mailboxes[axis]

    def _releasing(self, resource, script):
        yield from script
        self.taken.discard(resource)

    # --- script primitives: each yield is one cycle ---
    def _until(self, condition):
        while not condition():
            yield

    def _wait_ns(self, ns):
        end = self.k + self._cycles(ns)
        while self.k < end:
            yield

    def _polls(self, poller, count):
        """Until `count` more polls have been sent."""
        poller.start(self.k)
        done = poller.polls + count
        yield from self._until(lambda: poller.polls >= done)

    def _sdo(self, mailbox, request, answer, shows=()):
        """One SDO transfer: the request written, SM1 polled in the next cycles until the
        drive's answer is there."""
        yield [mailbox.write(*request)]
        for _ in range(SDO_EMPTY_POLLS):
            yield [mailbox.read()]
        yield [mailbox.read(answer, shows)]

    def _upload_count(self, mailbox, axis, shows=()):
        """1003h:00, expedited, 1 byte."""
        entries = self.entries[axis]
        yield from self._sdo(mailbox, (SDO_UPLOAD, ERROR_FIELD, 0),
                             (COE_SDO_RESPONSE, SDO_UPLOADED | EXPEDITED_BYTE, ERROR_FIELD, 0,
                              entries), shows)

    # --- the scripts ---
    def _lnk_001(self, inj):
        slave = self.first_servo + inj.axis
        yield from self._polls(self.counters, 2)  # the baseline, then one unchanged
        # symbol errors on the link into port 0 between frames: no frame lost, none forwarded
        self.counters.rise(slave, RX_ERROR, RX_ERRORS, inj.rule)
        yield from self._until(lambda: not self.counters.shows)

    def _lnk_002(self, inj):
        slave = self.first_servo + inj.axis
        yield from self._polls(self.counters, 2)
        # a link-down at port 1; inside the ring the next slave's port 0 is the link's other end
        self.counters.rise(slave, LOST_LINK + 1, 1, inj.rule)
        if slave + 1 < self.counters.slaves:
            self.counters.rise(slave + 1, LOST_LINK, 1, inj.rule)
        yield from self._until(lambda: not self.counters.shows)

    def _dc_001(self, inj):
        slave = self.first_servo + inj.axis
        yield from self._polls(self.dc, 3)  # in sync first
        self.dc.runs[slave] = list(DC_OUT_OF_SYNC_NS)
        self.dc.shows.append((slave, inj.rule))  # on the first read of the run only
        yield from self._until(lambda: slave not in self.dc.runs)
        yield from self._polls(self.dc, 1)  # back in sync: the run has ended

    def _mbx_003(self, inj):
        mailbox = self.mailbox(inj.axis)
        entries = self.entries[inj.axis]
        yield from self._upload_count(mailbox, inj.axis)
        if entries < MAX_ENTRIES:  # an entry the drive does not hold: expected, no finding
            yield from self._sdo(mailbox, (SDO_UPLOAD, ERROR_FIELD, entries + 1),
                                 (COE_SDO_REQUEST, SDO_ABORT, ERROR_FIELD, entries + 1,
                                  ABORT_NO_DATA))
        yield from self._sdo(mailbox, (SDO_UPLOAD, 0x2000, 0),
                             (COE_SDO_REQUEST, SDO_ABORT, 0x2000, 0, ABORT_NO_OBJECT),
                             [(inj.rule, None)])

    def _erh_001(self, inj):
        axis = inj.axis
        mailbox = self.mailbox(axis)
        yield from self._upload_count(mailbox, axis)  # at least PRELOGGED_ENTRIES
        yield from self._wait_ns(ERH_READ_GAP_NS)
        self.entries[axis] = 1  # the drive loses all entries but the newest
        yield from self._upload_count(mailbox, axis, [(inj.rule, None)])
        yield from self._wait_ns(ERH_READ_GAP_NS)
        # the NC clears the history (a download of 0): lower after that is no finding
        yield from self._sdo(mailbox, (SDO_DOWNLOAD | EXPEDITED_BYTE, ERROR_FIELD, 0, 0),
                             (COE_SDO_RESPONSE, SDO_DOWNLOADED, ERROR_FIELD, 0, 0))
        self.entries[axis] = 0
        yield from self._upload_count(mailbox, axis)


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

    def __init__(self, n_axes, encap, neighbours=None):
        self.rx = struct.Struct("<" + "iIh" * n_axes)
        self.tx = struct.Struct("<" + "qIIif4f" * n_axes)
        self.neighbours = neighbours or Neighbours(0, 0)
        nb = self.neighbours
        lrw_len = n_axes * (RX_SIZE + TX_SIZE) + nb.out_size + nb.in_size
        # frame header, LRW header, neighbours' outputs, outputs, neighbours' inputs, inputs,
        # WKC, FRMW header, DC time, WKC
        self.body = struct.Struct(f"<H BBIHH {nb.out_size}s {n_axes * RX_SIZE}s {nb.in_size}s "
                                  f"{n_axes * TX_SIZE}s H BBHHHH Q H")
        chain_len = self.body.size - 2
        self.ecat_header = chain_len | (1 << 12)
        self.lrw_len_word = lrw_len | LEN_MORE
        self.n_axes = n_axes
        self.zero_inputs = bytes(n_axes * TX_SIZE)
        self.prefix_master = link_header(encap, MASTER_MAC, self.body.size)
        self.prefix_returned = link_header(encap, RETURNED_MAC, self.body.size)
        self.pad = bytes(max(0, 60 - len(self.prefix_master) - self.body.size))

    def frame(self, returned, index, outputs, inputs, dc_time, wkc=None, nb_out=b"",
              nb_in=b""):
        n = self.n_axes
        if wkc is None:
            wkc = 3 * (n + self.neighbours.slaves) if returned else 0
        body = self.body.pack(self.ecat_header,
                              CMD_LRW, index, LOGICAL_ADDRESS, self.lrw_len_word, 0,
                              nb_out, outputs, nb_in, inputs, wkc,
                              CMD_FRMW, index, DC_ADP, DC_ADO, 8, 0,
                              dc_time, n if returned else 0)
        prefix = self.prefix_returned if returned else self.prefix_master
        return prefix + body + self.pad


class Neighbours:
    """Slaves of the servos' LRW that are not servos, before them in the ring: I/O terminals of
    one output and one input byte whose inputs change every cycle (an odd count puts the servos
    at odd offsets), then CiA 402 drives whose PDOs have a servo's 10 and 40 bytes."""

    def __init__(self, terminals, cia402, seed=0):
        self.terminals, self.cia402 = terminals, cia402
        self.slaves = terminals + cia402
        self.out_size = terminals + cia402 * RX_SIZE
        self.in_size = terminals + cia402 * TX_SIZE
        self.rng = random.Random(f"{seed}/neighbours")

    def outputs(self, k):
        terminals = bytes((1 << (k // 100 + i) % 8) for i in range(self.terminals))
        drive = struct.pack("<HiI", 0x000F, k * 100, 1000)  # control word, target, velocity
        return terminals + drive * self.cia402

    def inputs(self, k):
        terminals = bytes(self.rng.getrandbits(8) for _ in range(self.terminals))
        drives = b"".join(struct.pack("<HiIh", 0x1237, k * 100 + 7 * d, 1000, k % 200)
                          + bytes(TX_SIZE - 12) for d in range(self.cia402))
        return terminals + drives

    def servo_outputs(self, axis):
        return LOGICAL_ADDRESS + self.out_size + axis * RX_SIZE

    def servo_inputs(self, axis, n_axes):
        return LOGICAL_ADDRESS + self.out_size + n_axes * RX_SIZE + self.in_size + axis * TX_SIZE


class IoTask:
    """A second task: an LRW of its own at another logical address every `every` cycles, for
    an output terminal and an input terminal of IO_TASK_BYTES each (WKC 2 + 1)."""

    def __init__(self, every, seed=0):
        self.every = every
        self.rng = random.Random(f"{seed}/io-task")
        self.body = struct.Struct(f"<H BBIHH {2 * IO_TASK_BYTES}s H")
        self.ecat_header = (self.body.size - 2) | (1 << 12)

    def frame(self, returned, index, k, inputs):
        outputs = struct.pack("<I", k // self.every)
        data = outputs + (inputs if returned else bytes(IO_TASK_BYTES))
        body = self.body.pack(self.ecat_header, CMD_LRW, index, IO_TASK_ADDRESS,
                              2 * IO_TASK_BYTES, 0, data, 3 if returned else 0)
        prefix = link_header("eth", RETURNED_MAC if returned else MASTER_MAC, self.body.size)
        return prefix + body + bytes(max(0, 60 - len(prefix) - self.body.size))

    def new_inputs(self):
        return bytes(self.rng.getrandbits(8) for _ in range(IO_TASK_BYTES))


class AcyclicBuilder:
    """Packs both copies of an AcyclicFrame, each frame with an index of its own (counting)."""

    def __init__(self, encap):
        self.encap = encap
        self.index = 0

    def copies(self, frame, t_ns):
        """Both copies of a frame the master sends at t_ns."""
        self.index = (self.index + 1) & 0xFF
        return self._frame(False, frame, t_ns), self._frame(True, frame, t_ns)

    def _frame(self, returned, frame, t_ns):
        body = b""
        last = len(frame.datagrams) - 1
        for i, (command, adp, ado, sent, answer, wkc) in enumerate(frame.datagrams):
            data = answer if returned else sent
            data = data(t_ns) if callable(data) else data
            length = len(data) | (LEN_MORE if i < last else 0)
            body += struct.pack("<BBHHHH", command, self.index, adp, ado, length, 0) + data
            body += struct.pack("<H", wkc if returned else 0)
        body = struct.pack("<H", len(body) | (1 << 12)) + body
        prefix = link_header(self.encap, RETURNED_MAC if returned else MASTER_MAC, len(body))
        return prefix + body + bytes(max(0, 60 - len(prefix) - len(body)))


def write_layout_config(path, n_axes, neighbours, ready_mode, first_station=None):
    """The exact layout, for `ncservo validate --config` and the plugin's ncservo.config; with
    first_station, each axis's slave's station address too (STATION_RULES need it)."""
    with open(path, "w", encoding="ascii") as f:
        f.write("# The layout of gen_capture.py's capture.\n")
        f.write(f"servo_ready_mode = {ready_mode}\n")
        for a in range(n_axes):
            f.write(f"\n[[axis]]\nname = 'axis{a}'\n"
                    f"outputs = 0x{neighbours.servo_outputs(a):X}\n"
                    f"inputs = 0x{neighbours.servo_inputs(a, n_axes):X}\n")
            if first_station is not None:
                f.write(f"station = 0x{first_station + a:X}\n")


class PcapWriter:
    def __init__(self, out, nanosecond):
        self.out = out
        self.divisor = 1 if nanosecond else 1000
        self.record = struct.Struct("<IIII")
        self.count = 0  # frames written
        magic = 0xA1B23C4D if nanosecond else 0xA1B2C3D4
        out.write(struct.pack("<IHHiIII", magic, 2, 4, 0, 0, 65535, 1))

    def write(self, t_ns, data, interface=0):
        if interface:
            raise ValueError("a pcap has one interface")
        self.count += 1
        sec, frac = divmod(t_ns, 10**9)
        self.out.write(self.record.pack(sec, frac // self.divisor, len(data), len(data)))
        self.out.write(data)


class PcapngWriter:
    def __init__(self, out, link_types=(LINKTYPE_ETHERNET,)):
        self.out = out
        self.epb = struct.Struct("<IIIIIII")
        self.count = 0  # frames written
        shb_body = struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1)
        self._block(0x0A0D0D0A, shb_body)
        tsresol = struct.pack("<HHB3x", 9, 1, 9)  # if_tsresol = 10^-9
        for link_type in link_types:  # one IDB per interface, numbered in this order
            idb_body = struct.pack("<HHI", link_type, 0, 65535) + tsresol + struct.pack("<HH", 0, 0)
            self._block(1, idb_body)

    def _block(self, block_type, body):
        total = 12 + len(body)
        self.out.write(struct.pack("<II", block_type, total) + body + struct.pack("<I", total))

    def write(self, t_ns, data, interface=0):
        self.count += 1
        pad = -len(data) % 4
        total = 32 + len(data) + pad
        self.out.write(self.epb.pack(6, total, interface, t_ns >> 32, t_ns & 0xFFFFFFFF,
                                     len(data), len(data)))
        self.out.write(data + bytes(pad) + struct.pack("<I", total))


STAMP_SHAPES = {  # --capture-stamps: shape -> the length's range in us
    "bunched": (100, 100_000), "quantised": (1, 100_000), "late": (1, 10_000)}
BURST_STEP_NS = 2000  # records of one burst, in capture order
MIRROR_LAG_NS = 1000  # a mirrored copy after its original


def parse_capture_stamps(text, error):
    """SHAPE:LENGTH -> (shape, length in ns); `error` on anything else."""
    shape, _, length = text.partition(":")
    if shape not in STAMP_SHAPES:
        error(f"--capture-stamps {text}: SHAPE:LENGTH, SHAPE one of {', '.join(STAMP_SHAPES)}")
    units = {"us": 1, "ms": 1000}
    if length[-2:] not in units:
        error(f"--capture-stamps {text}: LENGTH in us or ms, e.g. {shape}:4ms")
    try:
        micros = float(length[:-2]) * units[length[-2:]]
    except ValueError:
        micros = -1
    low, high = STAMP_SHAPES[shape]
    if micros != int(micros) or not low <= micros <= high:
        error(f"--capture-stamps {text}: a whole number of us from {low} us to {high} us")
    return shape, int(micros) * 1000


class OfficePort:
    """The capturing PC's office port (--second-interface): a record every 0.5 to 7 ms, an ARP
    request of a neighbour (a quarter of them) or a UDP datagram between the PC and a neighbour
    or broadcast by one, each behind a Linux cooked (SLL v1) header."""

    PC = (bytes.fromhex("3c970e112233"), bytes((10, 20, 30, 5)))
    NEIGHBOURS = [(bytes.fromhex(f"a0b3cc0000{i:02x}"), bytes((10, 20, 30, 20 + i)))
                  for i in range(1, 5)]
    BROADCAST_IP = bytes((10, 20, 30, 255))
    SLL_HOST, SLL_BROADCAST, SLL_OUTGOING = 0, 1, 4  # packet types

    def __init__(self, seed):
        self.rng = random.Random(f"{seed}/office")
        self.next_ns = None
        self.ident = 0

    def records_until(self, t_ns):
        """The port's records stamped at or before t_ns (the first one after the first call)."""
        if self.next_ns is None:
            self.next_ns = t_ns + self._gap()
        while self.next_ns <= t_ns:
            yield self.next_ns, self._record()
            self.next_ns += self._gap()

    def _gap(self):
        return self.rng.randint(500, 7000) * 1000

    @staticmethod
    def _sll(packet_type, mac, protocol):
        return struct.pack(">HHH6s2xH", packet_type, 1, 6, mac, protocol)

    def _record(self):
        rng = self.rng
        mac, ip = rng.choice(self.NEIGHBOURS)
        if rng.random() < 0.25:  # who has (RFC 826)?
            target = rng.choice(self.NEIGHBOURS + [self.PC])[1]
            arp = struct.pack(">HHBBH6s4s6s4s", 1, 0x0800, 6, 4, 1, mac, ip, bytes(6), target)
            return self._sll(self.SLL_BROADCAST, mac, 0x0806) + arp
        kind = rng.choice((self.SLL_OUTGOING, self.SLL_HOST, self.SLL_BROADCAST))
        if kind == self.SLL_OUTGOING:
            sender, src, dst = self.PC[0], self.PC[1], ip
        else:
            sender, src = mac, ip
            dst = self.PC[1] if kind == self.SLL_HOST else self.BROADCAST_IP
        payload = bytes(rng.getrandbits(8) for _ in range(rng.randint(8, 400)))
        udp = struct.pack(">HHHH", rng.randint(50000, 50999), rng.randint(50000, 50999),
                          8 + len(payload), 0) + payload
        self.ident = (self.ident + 1) & 0xFFFF
        header = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), self.ident, 0x4000, 64,
                             17, 0, src, dst)
        total = sum(struct.unpack(">10H", header))
        while total > 0xFFFF:
            total = (total & 0xFFFF) + (total >> 16)
        header = header[:10] + struct.pack(">H", ~total & 0xFFFF) + header[12:]
        return self._sll(kind, sender, 0x0800) + header + udp


class CapturingPc:
    """What the capturing PC writes of each frame of the bus: the frame stamped by its clock
    (--capture-stamps), a mirrored copy right after it (--duplicate-records), and the office
    port's records before it (--second-interface). `count` is the record number of the last
    frame's original; `records` the record number of every frame of the bus, in order."""

    def __init__(self, writer, args):
        self.writer = writer
        self.shape, self.length_ns = args.capture_stamps or (None, 0)
        self.mirror = args.duplicate_records
        self.office = OfficePort(args.seed) if args.second_interface else None
        self.late = random.Random(f"{args.seed}/late")
        self.burst, self.in_burst = None, 0
        self.last_ns = 0
        self.count = 0
        self.records = []

    def _stamp(self, t_ns):
        if self.shape == "bunched":
            burst = t_ns // self.length_ns
            self.in_burst = self.in_burst + 1 if burst == self.burst else 0
            self.burst = burst
            return (burst + 1) * self.length_ns + self.in_burst * BURST_STEP_NS
        if self.shape == "quantised":
            return t_ns - t_ns % self.length_ns
        if self.shape == "late":
            return t_ns + self.late.randint(0, self.length_ns // 1000) * 1000
        return t_ns

    def write(self, t_ns, data):
        if not (self.shape or self.mirror or self.office):  # the bus's own times, as before
            self.writer.write(t_ns, data)
            self.count = self.writer.count
            self.records.append(self.count)
            return
        stamp = max(self._stamp(t_ns), self.last_ns)  # a PC's stamps never go back
        if self.office:
            for office_ns, record in self.office.records_until(stamp):
                self.writer.write(office_ns, record, interface=1)
        self.writer.write(stamp, data)
        self.count = self.writer.count
        self.records.append(self.count)
        self.last_ns = stamp
        if self.mirror:
            copy_ns = stamp if self.shape == "quantised" else stamp + MIRROR_LAG_NS
            self.writer.write(copy_ns, data)
            self.last_ns = copy_ns


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

    def write(self, t_ns, copy, outputs, inputs, frame=None):
        """`frame`: the record's number in the capture, when other records come between."""
        self.frame_number = frame if frame is not None else self.frame_number + 1
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

    def __init__(self, args, injections=(), expect=None, self_check=False):
        self.ncs, self.drives = [], []
        for axis in range(args.axes):
            plan = Plan(axis, args.axes, args.cycles, random.Random(f"{args.seed}/plan/{axis}"),
                        args.enable_by, args.idle_cycles, args.idle_all)
            self.ncs.append(Nc(axis, plan, random.Random(f"{args.seed}/nc/{axis}")))
            self.drives.append(Drive(axis, plan, args.cycle_us,
                                     random.Random(f"{args.seed}/drive/{axis}"), args.ready_mode))
        self.seed = args.seed
        self.cycle_ns = args.cycle_us * 1000
        self.k = 0
        # injections waiting, in the order of their start (then of the command line)
        self.pending = sorted((inj for inj in injections if not inj.acyclic),
                              key=lambda inj: (inj.start_cycle, inj.order))
        acyclic = [inj for inj in injections if inj.acyclic]
        first_servo = args.io_terminals + args.cia402  # the neighbours come first in the ring
        # --incident link-fault polls the counters too
        polled = acyclic or any(inj.rule in ("link-fault",) + tuple(STATION_RULES)
                                for inj in injections)
        self.acyclic = (Acyclic(acyclic, self, first_servo, first_servo + args.axes)
                        if polled else None)
        self.acyclic_frames = []  # this cycle's, sent after its frame
        self.bus = None  # the running bus injection's script
        self.directive = None  # this cycle's frame: None, DROP or LOST
        self.wkc = None  # this cycle's returned WKC, if not the expected one
        self.outage_cycles = set()  # --incident bus-outage: cycles whose master copy shows one
        self.expect = expect
        self.monitor = Monitor(self, args.ready_mode) if self_check else None

    def step(self, k):
        """Flat output and input values of every axis for cycle k."""
        self.k = k
        if self.pending or self.bus:
            self._inject(k)
        outputs = [nc.step(k) for nc in self.ncs]
        if self.directive == LOST:
            inputs = [drive.step(k, 0, 0, received=False) for drive in self.drives]
        else:
            inputs = [drive.step(k, o[0], o[1]) for drive, o in zip(self.drives, outputs)]
        if self.monitor:
            self.monitor.check(k, outputs, inputs)
        if self.acyclic:
            self.acyclic.observe(inputs)
            # none in a cycle lost or dropped: the scripts wait
            self.acyclic_frames = self.acyclic.step(k) if self.directive is None else []
        return outputs, inputs

    def _inject(self, k):
        """Start the injections that are due and can start, then step the bus injection."""
        waiting_axes = set()  # an axis whose earlier injection still waits keeps its order
        for inj in list(self.pending):
            if inj.start_cycle > k or self.bus:
                break
            if inj.bus:  # alone, with every axis idle
                if all(nc.injection is None and nc.settled() for nc in self.ncs):
                    self.pending.remove(inj)
                    self.bus = Injector(inj, self).run_bus()
                break
            nc = self.ncs[inj.axis]
            if inj.axis not in waiting_axes and nc.injection is None and nc.settled():
                self.pending.remove(inj)
                nc.scripts.append(Injector(inj, self).run_axis())
            else:
                waiting_axes.add(inj.axis)
        if self.bus:
            try:
                next(self.bus)
            except StopIteration:
                self.bus = None

    def unfinished(self):
        """Injections that did not start, or did not end, before the last cycle."""
        running = [str(nc.injection.inj) for nc in self.ncs if nc.injection is not None]
        return ([str(inj) for inj in self.pending] + running
                + (["a bus injection"] if self.bus else [])
                + (self.acyclic.unfinished() if self.acyclic else []))

    def deliver(self, inputs):
        """The returned copy reached the master: the NCs see the new status."""
        for nc, values in zip(self.ncs, inputs):
            nc.observe(values[1], values[2])

    def complete(self):
        return all(nc.done for nc in self.ncs)


def generate(args, out, truth_out, expect=None, incidents=None):
    neighbours = Neighbours(args.io_terminals, args.cia402, args.seed)
    builder = FrameBuilder(args.axes, args.encap, neighbours)
    io_task = IoTask(args.io_task_cycles, args.seed) if args.io_task_cycles else None
    acyclic = AcyclicBuilder(args.encap)
    io_inputs = bytes(IO_TASK_BYTES)
    echoed = builder.zero_inputs  # --echo-inputs: the last inputs received
    nb_echoed = bytes(neighbours.in_size)
    if args.format == "pcapng":
        link_types = (LINKTYPE_ETHERNET,) + ((LINKTYPE_LINUX_SLL,) if args.second_interface else ())
        writer = CapturingPc(PcapngWriter(out, link_types), args)
    else:
        writer = CapturingPc(PcapWriter(out, args.nanosecond), args)
    # the truth and the findings name the capture's records once other records come between
    numbered = args.duplicate_records or args.second_interface
    if expect and numbered:
        expect.records = writer.records
    truth = TruthWriter(truth_out, builder) if truth_out else None
    session = Session(args, args.inject + args.incident, expect, args.self_check)
    sew_error = [False] * args.axes  # per axis, in the last returned copy written
    loss_rng = random.Random(f"{args.seed}/loss")
    cycle_ns, delay_ns = args.cycle_us * 1000, args.return_delay_us * 1000
    dc_start = T0_NS - DC_EPOCH_OFFSET_NS + DC_REFERENCE_OFF_NS
    want_master = args.copies in ("both", "master")
    want_returned = args.copies in ("both", "returned")
    chain = itertools.chain.from_iterable
    for k in range(args.cycles):
        outputs, inputs = session.step(k)
        out_bytes = builder.rx.pack(*chain(outputs))
        t_ns = T0_NS + k * cycle_ns
        index = k & 0xFF
        directive = session.directive
        nb_out, nb_in = neighbours.outputs(k), neighbours.inputs(k)
        if want_master and directive != DROP:
            writer.write(t_ns, builder.frame(False, index, out_bytes, echoed, 0, nb_out=nb_out,
                                             nb_in=nb_echoed))
            if incidents is not None and k in session.outage_cycles:
                incidents.append({"kind": "bus-outage", "axis": None, "frame": writer.count,
                                  "cause": "communication-loss"})
            if truth:
                truth.write(t_ns, "master", out_bytes, None, writer.count if numbered else None)
            if expect:
                expect.frame(t_ns, k, MASTER)
        if directive == LOST or (args.loss and loss_rng.random() < args.loss):
            io_inputs = write_io_task(writer, io_task, k, t_ns, delay_ns, io_inputs, expect)
            write_acyclic(writer, acyclic, session.acyclic_frames, k, t_ns, cycle_ns, delay_ns,
                          io_task, args.copies, expect)
            continue
        session.deliver(inputs)
        in_bytes = builder.tx.pack(*chain(inputs))
        if args.echo_inputs:
            echoed, nb_echoed = in_bytes, nb_in
        if want_returned and directive != DROP:
            t_ret = t_ns + delay_ns
            frame = builder.frame(True, index, out_bytes, in_bytes, dc_start + t_ret - T0_NS,
                                  session.wkc, nb_out, nb_in)
            writer.write(t_ret, frame)
            if incidents is not None:
                note_drive_faults(incidents, sew_error, inputs, session.drives, writer.count)
            if truth:
                truth.write(t_ret, "returned", out_bytes, in_bytes,
                            writer.count if numbered else None)
            if expect:
                expect.frame(t_ret, k, RETURNED)
        io_inputs = write_io_task(writer, io_task, k, t_ns, delay_ns, io_inputs, expect)
        write_acyclic(writer, acyclic, session.acyclic_frames, k, t_ns, cycle_ns, delay_ns,
                      io_task, args.copies, expect)
    unfinished = session.unfinished()
    if unfinished:
        print("gen_capture: injections not done before the last cycle (more --cycles, or "
              "earlier @SECONDS): " + ", ".join(unfinished), file=sys.stderr)
    return session.complete() and not unfinished


def note_drive_faults(incidents, sew_error, inputs, drives, frame):
    """--incidents: a drive fault is the returned copy in which its SEW.ServoErrors first
    reads 1; its cause is the one the drive was given when it faulted."""
    for axis, values in enumerate(inputs):
        error = bool(values[2] & SEW_SERVO_ERRORS)
        if error and not sew_error[axis]:
            cause = drives[axis].cause_id
            if cause is None:
                raise SystemExit(f"gen_capture: axis {axis} faulted at frame {frame} for no "
                                 "cause the incident truth knows")
            incidents.append({"kind": "drive-fault", "axis": axis, "frame": frame,
                              "cause": cause})
        sew_error[axis] = error


def write_io_task(writer, io_task, k, t_ns, delay_ns, io_inputs, expect):
    """The second task's frame after this cycle's (both copies); its echoed inputs next time.
    Its frames count as the cycle's returned copy for the findings' frame windows."""
    if io_task is None or k % io_task.every:
        return io_inputs
    index = (k + 0x80) & 0xFF
    t_io = t_ns + 2 * delay_ns
    writer.write(t_io, io_task.frame(False, index, k, io_inputs))
    returned = io_task.new_inputs()
    writer.write(t_io + delay_ns, io_task.frame(True, index, k, returned))
    if expect:
        expect.frame(t_io, k, RETURNED)
        expect.frame(t_io + delay_ns, k, RETURNED)
    return returned


def write_acyclic(writer, builder, frames, k, t_ns, cycle_ns, delay_ns, io_task, copies, expect):
    """The master's acyclic frames of cycle k (both copies, or the one captured), spread evenly
    between the cycle's last frame and the next cycle's.  They count as the cycle's returned
    copy for the findings' frame windows; the findings they show are due exactly on their
    returned copies."""
    if not frames:
        return
    io_frames = io_task is not None and k % io_task.every == 0
    t_from = t_ns + (3 if io_frames else 1) * delay_ns
    wanted = (False, True) if copies == "both" else (copies == "returned",)
    step = max(1, (t_ns + cycle_ns - t_from) // (len(frames) * len(wanted) + 1))
    t = t_from
    for frame in frames:
        master, returned = builder.copies(frame, t + step)
        for is_returned in wanted:
            t += step
            writer.write(t, returned if is_returned else master)
            if expect:
                expect.frame(t, k, RETURNED)
                if is_returned:
                    for rule, axis in frame.shows:
                        expect.add_last_frame(rule, axis)


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--axes", type=int, default=4, help="servo axes, 1..29 (default 4)")
    p.add_argument("--cycles", type=int, default=2000, help="cycles, at least 200 (default 2000)")
    p.add_argument("--cycle-us", type=int, default=1000, help="cycle time in us (default 1000)")
    p.add_argument("--return-delay-us", type=int, default=20,
                   help="returned copy after the master copy, us (default 20)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--enable-by", type=int, metavar="CYCLE",
                   help="every axis enabled before CYCLE, whatever the run length (default: "
                        "axis 0 at 2%% of the cycles, the others staggered after it)")
    p.add_argument("--encap", choices=("eth", "vlan", "qinq", "udp"), default="eth")
    p.add_argument("--format", choices=("pcap", "pcapng"), default="pcap")
    p.add_argument("--nanosecond", action="store_true", help="pcap with nanosecond timestamps")
    p.add_argument("--copies", choices=("both", "master", "returned"), default="both")
    p.add_argument("--loss", type=float, default=0.0,
                   help="probability of losing a returned copy (default 0)")
    p.add_argument("--ready-mode", type=int, choices=(0, 1), default=0,
                   help="the drives' Servo_Ready_Mode (default 0)")
    p.add_argument("--inject", action="append", default=[], metavar="RULE[@SECONDS][:AXIS]",
                   help="inject a violation of RULE (repeatable; see the module docstring)")
    p.add_argument("--incident", action="append", default=[],
                   metavar="KIND[@SECONDS][:AXIS]",
                   help="a drive fault with the chain its incident cause needs: "
                        + ", ".join(sorted(CHAINS)) + " (repeatable; see the module docstring)")
    p.add_argument("--incidents", metavar="FILE",
                   help="JSON file of the incidents (drive faults, their frames and causes) "
                        "`ncservo validate` must list")
    p.add_argument("--findings", metavar="FILE",
                   help="JSON file of the findings the injections must produce")
    p.add_argument("--self-check", action="store_true",
                   help="assert that every axis not under an injection conforms "
                        "(on with --findings)")
    p.add_argument("--list-rules", action="store_true",
                   help="print the rules --inject can violate, one per line, and exit")
    p.add_argument("--list-station-rules", action="store_true",
                   help="print the rules whose injection the validator judges only with the "
                        "layout's stations (--layout-config names them), one per line, and exit")
    p.add_argument("--io-terminals", type=int, default=0, metavar="N",
                   help="N I/O terminals (1 output and 1 input byte, inputs changing every "
                        "cycle) before the servos in their LRW (default 0)")
    p.add_argument("--cia402", type=int, default=0, metavar="N",
                   help="N CiA 402 drives with 10/40-byte PDOs before the servos (default 0)")
    p.add_argument("--idle-cycles", type=int, default=0, metavar="N",
                   help="the drives ready and nothing enabled for the first N cycles")
    p.add_argument("--idle-all", action="store_true",
                   help="the drives ready and nothing enabled in the whole capture")
    p.add_argument("--io-task-cycles", type=int, default=0, metavar="N",
                   help="a second task: an I/O frame with its own LRW every N cycles")
    p.add_argument("--echo-inputs", action="store_true",
                   help="master copies carry the last inputs received, as SOEM's do")
    p.add_argument("--layout-config", metavar="FILE",
                   help="write the exact layout as a configuration file (TOML)")
    p.add_argument("--capture-stamps", metavar="SHAPE:LENGTH",
                   help="how the capturing PC stamps the records: bunched, quantised or late, "
                        "LENGTH in us or ms (see the module docstring)")
    p.add_argument("--duplicate-records", action="store_true",
                   help="every record twice, as a switch port mirroring both directions")
    p.add_argument("--second-interface", action="store_true",
                   help="pcapng only: the PC's office port as interface 1 (Linux cooked)")
    p.add_argument("-o", "--output", help="capture file to write (required)")
    p.add_argument("--truth", help="JSON Lines truth file to write")
    args = p.parse_args(argv)
    if args.list_rules or args.list_station_rules:
        return args
    if not args.output:
        p.error("the following arguments are required: -o/--output")
    if not 1 <= args.axes <= MAX_AXES:
        p.error("--axes must be 1..29 (one LRW of at most 1486 bytes)")
    if args.cycles < 200:
        p.error("--cycles must be at least 200 for the session to fit")
    if args.enable_by is not None and not 8 <= args.enable_by <= args.cycles // 10:
        p.error("--enable-by must be 8..cycles/10, so the enables end before the rest of the session")
    if not 0 < args.return_delay_us < args.cycle_us:
        p.error("--return-delay-us must be positive and below --cycle-us")
    if not 0 <= args.loss < 1:
        p.error("--loss must be in [0, 1)")
    if args.loss and (args.inject or args.findings):
        p.error("--inject and --findings need a capture without random --loss")
    if args.io_terminals < 0 or args.cia402 < 0:
        p.error("--io-terminals and --cia402 cannot be negative")
    if (args.axes + args.cia402) * (RX_SIZE + TX_SIZE) + 2 * args.io_terminals > \
            MAX_AXES * (RX_SIZE + TX_SIZE):
        p.error("the servos and their neighbours must fit one LRW of at most 1450 bytes")
    if args.idle_all and (args.inject or args.idle_cycles):
        p.error("--idle-all: nothing is enabled, so no --inject and no --idle-cycles")
    if not 0 <= args.idle_cycles <= args.cycles - 200:
        p.error("--idle-cycles must leave at least 200 cycles for the session")
    if args.io_task_cycles and not 2 <= args.io_task_cycles:
        p.error("--io-task-cycles must be 2 or more")
    if args.io_task_cycles and any(rule.partition("@")[0].partition(":")[0].upper() in BUS_RULES
                                   for rule in args.inject):
        p.error("--io-task-cycles: no bus (COM-*) injections beside the second task")
    if args.incidents and (args.inject or args.loss or args.copies != "both"):
        p.error("--incidents: no --inject or --loss, and both copies (its truth knows the "
                "causes of its own chains only)")
    if args.capture_stamps:
        args.capture_stamps = parse_capture_stamps(args.capture_stamps, p.error)
    if args.second_interface and args.format != "pcapng":
        p.error("--second-interface: a pcap holds one interface; give --format pcapng")
    if args.findings:
        args.self_check = True
    args.inject = [parse_injection(text, i, args, p.error) for i, text in enumerate(args.inject)]
    args.incident = [parse_chain(text, len(args.inject) + i, args, p.error)
                     for i, text in enumerate(args.incident)]
    if args.encap == "udp" and args.axes > 28:
        print("gen_capture: warning: frames of more than 28 axes in UDP exceed the Ethernet MTU",
              file=sys.stderr)
    return args


def main(argv=None):
    args = parse_args(argv)
    if args.list_rules:
        print("\n".join(sorted(INJECTABLE)))
        return 0
    if args.list_station_rules:
        print("\n".join(sorted(STATION_RULES)))
        return 0
    if args.layout_config:
        stations = any(inj.rule in STATION_RULES for inj in args.inject)
        write_layout_config(args.layout_config, args.axes,
                            Neighbours(args.io_terminals, args.cia402), args.ready_mode,
                            FIRST_STATION + args.io_terminals + args.cia402 if stations else None)
    truth_out = open(args.truth, "w", encoding="ascii", buffering=1 << 20) if args.truth else None
    expect = Expectations(args.cycle_us * 1000, args.return_delay_us * 1000) \
        if args.findings else None
    incidents = [] if args.incidents else None
    try:
        with open(args.output, "wb", buffering=1 << 20) as out:
            complete = generate(args, out, truth_out, expect, incidents)
    finally:
        if truth_out:
            truth_out.close()
    if incidents is not None:
        with open(args.incidents, "w", encoding="ascii") as f:
            json.dump({"incidents": incidents}, f, indent=1)
            f.write("\n")
    if not complete:
        print("gen_capture: the session did not finish in --cycles cycles", file=sys.stderr)
        return 1
    if expect:
        try:
            expected = expect.resolve()
        except ValueError as e:
            print(f"gen_capture: {e}", file=sys.stderr)
            return 1
        injected = {inj.rule for inj in args.inject}
        document = {"expected": expected,
                    "companions": {rule: COMPANIONS[rule] for rule in sorted(injected)
                                   if rule in COMPANIONS}}
        with open(args.findings, "w", encoding="ascii") as f:
            json.dump(document, f, indent=1)
            f.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

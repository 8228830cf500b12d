"""Ground side of ccmap_app (integrations/cfs/ccmap_app): command encoding, telemetry decoding.

Python 3 standard library only. A command is a CCSDS packet: the big-endian 6-byte primary
header (message ID, 0xC000, total length - 7), the 2-byte command secondary header (function
code, checksum) and the payload in the flight cpu's byte order (little-endian here, as on
x86-64 and aarch64). A telemetry packet has a 16-byte header (primary, 6-byte time, 4 spare)
before its payload. Commands go to ci_lab (UDP 1234); to_lab sends telemetry to UDP 1235 once
enabled (enable_output()). docs/integration.md, "cFS", shows the use.

    python3 ccmap_ground.py noop            # one command to 127.0.0.1:1234
    python3 ccmap_ground.py listen 10       # print ccmap telemetry and events for 10 s
"""
import socket
import struct
import sys
import time

CMD_PORT = 1234
TLM_PORT = 1235

# Message IDs on the sample mission's cpu1 (0x1800 | topic for commands, 0x0800 | topic for telemetry).
CCMAP_CMD_MID = 0x18A0
CCMAP_SEND_HK_MID = 0x18A1
CCMAP_HK_TLM_MID = 0x08A1
CCMAP_FRAME_READY_MID = 0x18A2
CCMAP_PRODUCT_TLM_MID = 0x08A3
CCMAP_FEED_CMD_MID = 0x18A4
TO_LAB_CMD_MID = 0x1880
CFE_EVS_LONG_EVENT_MID = 0x0808

# ccmap_app function codes (config/default_ccmap_app_fcncodes.h).
NOOP, RESET_COUNTERS, CLEAR, SAVE, LOAD, PUBLISH, LOAD_TABLE = range(7)
PATH_LEN = 64                     # CFE_MISSION_MAX_PATH_LEN

# Event IDs (fsw/inc/ccmap_app_eventids.h), the ones a ground operator watches.
EID = {
    "INIT": 1, "NOOP": 2, "RESET": 3, "CLEAR": 4, "SAVE": 5, "LOAD": 6, "PUBLISH": 7, "TBL": 8,
    "MID_ERR": 20, "CC_ERR": 21, "LEN_ERR": 22, "PIPE_ERR": 23, "INIT_ERR": 24, "TBL_VAL_ERR": 25,
    "TBL_ERR": 26, "FRAME_ERR": 27, "UPDATE_ERR": 28, "BUDGET_ERR": 29, "FILE_ERR": 30,
    "SNAPSHOT_ERR": 31, "CLEAR_ERR": 32, "PUBLISH_ERR": 33, "HEALTH_ERR": 34, "LIB_FAULT": 35,
}

HK_FIELDS = (
    "CommandCounter CommandErrorCounter FramesAccepted FramesRefused FramesDropped PointsReceived "
    "PointsUsed PointsSkippedBudget LastFrameUs LastLibraryUs MaxFrameUs BudgetOverruns CycleBudgetUs "
    "TableUpdates TableRefusals FileErrors ProductSequence ProductCrc ProductCellsCrc ProductBytes "
    "LastStatus HealthState MapInitialised ObservedCells CorruptedCells ParamsCrc MapSequence "
    "LibraryFaults CoverageTau OutlierGateSigma FramePointBudget").split()
HK_FORMAT = "<20I2i6I2fI"
PRODUCT_FIELDS = "Sequence Crc CellsCrc Bytes Status".split()
PRODUCT_FORMAT = "<4Ii"

# The parameter table (config/default_ccmap_app_tbl.h), in field order.
TABLE_FIELDS = (
    "FinestCellWidthM WeightLimit CoverageTau MinWeight ObstacleFraction MaxInclination "
    "OutlierGateSigma FramePointBudget FrameTimeBudgetUs FreeSpaceRays CycleBudgetUs").split()
TABLE_FORMAT = "<7f2IfI"
TBL_FILE_HEADERS = 64 + 52        # CFE_FS_Header_t + CFE_TBL_File_Hdr_t (big-endian)


def command(mid, code, payload=b""):
    """A CCSDS command packet; the checksum makes the XOR of all its bytes 0xFF."""
    length = 8 + len(payload)
    head = struct.pack(">HHHB", mid, 0xC000, length - 7, code)
    checksum = 0xFF
    for byte in head + payload:
        checksum ^= byte
    return head + bytes([checksum]) + payload


def _text(value, size):
    raw = value.encode()
    if len(raw) >= size:
        raise ValueError(f"{value!r} does not fit {size} bytes with its NUL")
    return raw.ljust(size, b"\0")


def ccmap_command(code, path=None):
    """A ccmap_app command; SAVE, LOAD and LOAD_TABLE take an OSAL path ("/cf/map.snap")."""
    return command(CCMAP_CMD_MID, code, b"" if path is None else _text(path, PATH_LEN))


def feed_command(path):
    """ccmap_feed (the test's producer): read this frame file into a slot and announce it."""
    return command(CCMAP_FEED_CMD_MID, 1, _text(path, PATH_LEN))


def enable_output(ip="127.0.0.1"):
    """to_lab's OUTPUT_ENABLE: telemetry to ip:1235."""
    return command(TO_LAB_CMD_MID, 6, _text(ip, 16))


def table_file(template, **values):
    """A parameter-table file: the headers of a built table file (template: its bytes) and a new
    image, the template's values replaced by `values` (field names of TABLE_FIELDS)."""
    size = struct.unpack_from(">I", template, 64 + 8)[0]
    if size != struct.calcsize(TABLE_FORMAT) or len(template) != TBL_FILE_HEADERS + size:
        raise ValueError("not a ccmap_app parameter table file")
    fields = dict(zip(TABLE_FIELDS, struct.unpack_from(TABLE_FORMAT, template, TBL_FILE_HEADERS)))
    unknown = set(values) - set(fields)
    if unknown:
        raise ValueError(f"unknown table fields {sorted(unknown)}")
    fields.update(values)
    return template[:TBL_FILE_HEADERS] + struct.pack(TABLE_FORMAT, *(fields[f] for f in TABLE_FIELDS))


def message_id(packet):
    return struct.unpack_from(">H", packet)[0] if len(packet) >= 6 else None


def decode(packet):
    """(kind, fields) for ccmap housekeeping ("hk"), product summaries ("product") and events
    ("event": app, id, type, text); (None, None) for anything else or a packet of the wrong size."""
    mid = message_id(packet)
    body = packet[16:]
    if mid == CCMAP_HK_TLM_MID and len(body) == struct.calcsize(HK_FORMAT):
        return "hk", dict(zip(HK_FIELDS, struct.unpack(HK_FORMAT, body)))
    if mid == CCMAP_PRODUCT_TLM_MID and len(body) == struct.calcsize(PRODUCT_FORMAT):
        return "product", dict(zip(PRODUCT_FIELDS, struct.unpack(PRODUCT_FORMAT, body)))
    if mid == CFE_EVS_LONG_EVENT_MID and len(body) >= 32 + 1:
        app = body[:20].split(b"\0")[0].decode(errors="replace")
        event_id, event_type = struct.unpack_from("<HH", body, 20)
        text = body[32:].split(b"\0")[0].decode(errors="replace")
        return "event", {"app": app, "id": event_id, "type": event_type, "text": text}
    return None, None


class Link:
    """One UDP socket pair: send() to ci_lab, receive() from to_lab."""

    def __init__(self, host="127.0.0.1", cmd_port=CMD_PORT, tlm_port=TLM_PORT):
        self.address = (host, cmd_port)
        self.tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.rx.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.rx.bind(("0.0.0.0", tlm_port))

    def send(self, packet):
        self.tx.sendto(packet, self.address)

    def receive(self, timeout):
        """The next decoded ccmap packet (kind, fields), or (None, None) after timeout s."""
        end = time.monotonic() + timeout
        while True:
            left = end - time.monotonic()
            if left <= 0:
                return None, None
            self.rx.settimeout(left)
            try:
                packet = self.rx.recv(65536)
            except socket.timeout:
                return None, None
            kind, fields = decode(packet)
            if kind is not None:
                return kind, fields

    def close(self):
        self.tx.close()
        self.rx.close()


def main(argv):
    if len(argv) < 2:
        print(__doc__)
        return 2
    link = Link()
    try:
        verb = argv[1]
        if verb == "listen":
            link.send(enable_output())
            end = time.monotonic() + float(argv[2] if len(argv) > 2 else 10)
            while time.monotonic() < end:
                kind, fields = link.receive(end - time.monotonic())
                if kind:
                    print(kind, fields)
            return 0
        codes = {"noop": NOOP, "reset": RESET_COUNTERS, "clear": CLEAR, "save": SAVE, "load": LOAD,
                 "publish": PUBLISH, "load_table": LOAD_TABLE}
        if verb not in codes:
            print(f"unknown command {verb!r}: {' '.join(codes)} or listen")
            return 2
        link.send(ccmap_command(codes[verb], argv[2] if verb in ("save", "load", "load_table") else None))
        return 0
    finally:
        link.close()


if __name__ == "__main__":
    sys.exit(main(sys.argv))

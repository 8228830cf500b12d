"""Checks of ccmap_ground against independent references: the to_lab enable packet spelled out
byte for byte in ../shared/cfs/README.md, the CCSDS rules (length = total - 7, XOR of a command
0xFF) and the C payloads' field counts. Run: python3 -m unittest (from this folder); the cFS test
(integrations/cfs/test/run_cfs_test.py) runs it first."""
import struct
import unittest

import ccmap_ground as g


class Encoding(unittest.TestCase):
    def test_enable_packet_is_the_documented_one(self):
        packet = g.enable_output("127.0.0.1")
        self.assertEqual(packet[:7], bytes([0x18, 0x80, 0xC0, 0x00, 0x00, 0x11, 0x06]))
        self.assertEqual(packet[8:], b"127.0.0.1" + bytes(7))
        self.assertEqual(len(packet), 24)

    def test_commands_follow_ccsds(self):
        for packet in (g.ccmap_command(g.NOOP), g.ccmap_command(g.SAVE, "/cf/m.snap"), g.feed_command("/cf/f.bin")):
            self.assertEqual(struct.unpack_from(">H", packet, 4)[0], len(packet) - 7)
            xor = 0
            for byte in packet:
                xor ^= byte
            self.assertEqual(xor, 0xFF)
        self.assertEqual(len(g.ccmap_command(g.NOOP)), 8)
        self.assertEqual(len(g.ccmap_command(g.LOAD, "/cf/m.snap")), 8 + 64)
        with self.assertRaises(ValueError):
            g.ccmap_command(g.SAVE, "/cf/" + "x" * 60)

    def test_formats_have_one_field_a_name(self):
        self.assertEqual(len(g.HK_FIELDS), len(struct.unpack(g.HK_FORMAT, bytes(struct.calcsize(g.HK_FORMAT)))))
        self.assertEqual(struct.calcsize(g.HK_FORMAT), 4 * len(g.HK_FIELDS))
        self.assertEqual(len(g.TABLE_FIELDS), 11)
        self.assertEqual(struct.calcsize(g.TABLE_FORMAT), 4 * len(g.TABLE_FIELDS))

    def test_decode_hk_and_event(self):
        values = list(range(len(g.HK_FIELDS)))
        values[g.HK_FIELDS.index("CoverageTau")] = 0.5
        values[g.HK_FIELDS.index("OutlierGateSigma")] = 3.0
        packet = struct.pack(">HHH", g.CCMAP_HK_TLM_MID, 0xC000, 0) + bytes(10) + struct.pack(g.HK_FORMAT, *values)
        kind, fields = g.decode(packet)
        self.assertEqual(kind, "hk")
        self.assertEqual(fields["FramesDropped"], 4)
        self.assertEqual(fields["CoverageTau"], 0.5)
        event = (struct.pack(">HHH", g.CFE_EVS_LONG_EVENT_MID, 0xC000, 0) + bytes(10) + b"CCMAP_APP".ljust(20, b"\0")
                 + struct.pack("<HHII", 25, 3, 0x42, 1) + b"refused".ljust(122, b"\0") + bytes(2))
        self.assertEqual(g.decode(event), ("event", {"app": "CCMAP_APP", "id": 25, "type": 3, "text": "refused"}))
        self.assertEqual(g.decode(packet[:-1]), (None, None))

    def test_table_file_replaces_only_the_named_field(self):
        image = struct.pack(g.TABLE_FORMAT, 0.04, 1000.0, 0.8, 5.0, 0.75, 0.36, 3.0, 0, 0, 128.0, 80000)
        headers = bytearray(g.TBL_FILE_HEADERS)
        struct.pack_into(">I", headers, 64 + 8, len(image))
        out = g.table_file(bytes(headers) + image, CoverageTau=1.5)
        self.assertEqual(out[:g.TBL_FILE_HEADERS], bytes(headers))
        fields = dict(zip(g.TABLE_FIELDS, struct.unpack_from(g.TABLE_FORMAT, out, g.TBL_FILE_HEADERS)))
        self.assertEqual(fields["CoverageTau"], 1.5)
        self.assertEqual(fields["CycleBudgetUs"], 80000)
        with self.assertRaises(ValueError):
            g.table_file(bytes(headers) + image, NoSuchField=1)


if __name__ == "__main__":
    unittest.main()

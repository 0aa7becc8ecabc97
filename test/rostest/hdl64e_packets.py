"""HDL-64E data packets built byte by byte for the Python rostests (independent of the C++
encoder): 12 blocks of [block id, azimuth in 1/100 deg, 32 x (distance in 2 mm, intensity)],
upper (0xEEFF, lasers 0-31) and lower (0xDDFF, lasers 32-63) blocks alternating, then a 4-byte
timestamp and 2 status bytes. Also a minimal pcap writer (Ethernet/IPv4/UDP to port 2368)."""
import struct

DISTANCE_RAW = 5000          # 10 m at 2 mm per unit
SILENT_UPPER_LASER = 7       # distance 0 (no return) in every upper block
POINTS_PER_PACKET = 6 * (32 - 1) + 6 * 32


def make_packet(first_azimuth_deg, timestamp_us):
    """One packet whose six firings are 1 deg apart starting at first_azimuth_deg."""
    out = bytearray()
    for block in range(12):
        upper = block % 2 == 0
        azimuth = int(round((first_azimuth_deg + block // 2) * 100)) % 36000
        out += struct.pack('<HH', 0xEEFF if upper else 0xDDFF, azimuth)
        for laser in range(32):
            distance = 0 if (upper and laser == SILENT_UPPER_LASER) else DISTANCE_RAW
            out += struct.pack('<HB', distance, 100)
    out += struct.pack('<IBB', timestamp_us, 0, 0)
    assert len(out) == 1206
    return bytes(out)


def _ip_checksum(header):
    total = sum(struct.unpack('!10H', header))
    while total >> 16:
        total = (total & 0xFFFF) + (total >> 16)
    return ~total & 0xFFFF


def write_pcap(path, packets_with_stamps, port=2368):
    """Writes (payload, stamp_s) pairs as Ethernet/IPv4/UDP frames from 192.168.3.43."""
    with open(path, 'wb') as f:
        f.write(struct.pack('<IHHiIII', 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1))
        for payload, stamp in packets_with_stamps:
            udp = struct.pack('!HHHH', port, port, 8 + len(payload), 0) + payload
            ip = bytearray(struct.pack('!BBHHHBBH4s4s', 0x45, 0, 20 + len(udp), 0, 0x4000, 64,
                                       17, 0, bytes([192, 168, 3, 43]),
                                       bytes([255, 255, 255, 255])))
            ip[10:12] = struct.pack('!H', _ip_checksum(bytes(ip)))
            frame = b'\xff' * 6 + b'\x60\x76\x88\x00\x00\x00' + b'\x08\x00' + bytes(ip) + udp
            sec = int(stamp)
            usec = int(round((stamp - sec) * 1e6))
            f.write(struct.pack('<IIII', sec, usec, len(frame), len(frame)))
            f.write(frame)

#!/usr/bin/env python3
"""Bags recorded by velodyne drivers connect: a bag written here with the connection type
velodyne_msgs/VelodyneScan (same MD5 as urban_detection/VelodyneScan) is played with
`rosbag play` into PacketToCloud, which must decode every revolution.

The packets are built byte by byte (hdl64e_packets.py, not the C++ encoder), so the test also
checks the packet layout independently.
"""
import io
import math
import os
import subprocess
import tempfile
import threading
import time
import unittest

import rosbag
import rosgraph
import rospy
import rostest
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointCloud2
from urban_detection.msg import VelodynePacket, VelodyneScan

from hdl64e_packets import POINTS_PER_PACKET, make_packet

PACKETS_PER_SCAN = 20
SCANS = 5


def make_scan(index):
    scan = VelodyneScan()
    scan.header.frame_id = 'velodyne'
    start = rospy.Time(1000, 100000000 * index)
    for p in range(PACKETS_PER_SCAN):
        packet = VelodynePacket()
        packet.stamp = start + rospy.Duration.from_sec(p * 0.000288)
        packet.data = make_packet(0.5 + 6 * p, p * 288)
        scan.packets.append(packet)
    scan.header.stamp = scan.packets[-1].stamp  # velodyne_driver: the last packet's stamp
    return scan


class BagWithVelodyneMsgsType(unittest.TestCase):
    def setUp(self):
        self.clouds = []
        self.lock = threading.Lock()

    def on_cloud(self, msg):
        with self.lock:
            self.clouds.append(msg)

    def wait_for_packet_subscriber(self, timeout_s):
        master = rosgraph.Master('/bag_test')
        end = time.time() + timeout_s
        while time.time() < end:
            _, subscribers, _ = master.getSystemState()
            if any(topic == '/velodyne_packets' and nodes for topic, nodes in subscribers):
                return True
            time.sleep(0.05)
        return False

    def test_foreign_type_name_is_decoded(self):
        bag_path = os.path.join(tempfile.mkdtemp(), 'velodyne_msgs.bag')
        scans = [make_scan(i) for i in range(SCANS)]
        with rosbag.Bag(bag_path, 'w') as bag:
            for scan in scans:
                buffer = io.BytesIO()
                scan.serialize(buffer)
                bag.write('/velodyne_packets',
                          ('velodyne_msgs/VelodyneScan', buffer.getvalue(),
                           '50804fc9533a0e579e6322c04ae70566', VelodyneScan),
                          t=scan.header.stamp, raw=True)
        with rosbag.Bag(bag_path) as bag:
            info = bag.get_type_and_topic_info()
            self.assertEqual(info.topics['/velodyne_packets'].msg_type,
                             'velodyne_msgs/VelodyneScan')
            self.assertEqual(info.topics['/velodyne_packets'].message_count, SCANS)

        sub = rospy.Subscriber('/velodyne_points', PointCloud2, self.on_cloud, queue_size=20)
        # PacketToCloud is lazy: it subscribes to the packets once we listen to the points.
        self.assertTrue(self.wait_for_packet_subscriber(20.0),
                        'PacketToCloud never subscribed to /velodyne_packets')
        play = subprocess.run(['rosbag', 'play', '--quiet', '--wait-for-subscribers', bag_path],
                              timeout=40)
        self.assertEqual(play.returncode, 0)
        end = time.time() + 10.0
        while time.time() < end and len(self.clouds) < SCANS:
            time.sleep(0.05)
        sub.unregister()

        with self.lock:
            clouds = list(self.clouds)
        self.assertEqual(len(clouds), SCANS)
        for scan, cloud in zip(scans, clouds):
            self.assertEqual(cloud.header.frame_id, 'velodyne')
            # The cloud keeps the driver's scan stamp (PCL keeps microseconds).
            self.assertAlmostEqual((cloud.header.stamp - scan.packets[-1].stamp).to_sec(), 0.0,
                                   delta=1e-6)
            self.assertEqual(cloud.width * cloud.height, PACKETS_PER_SCAN * POINTS_PER_PACKET)
            names = [f.name for f in cloud.fields]
            self.assertEqual(names, ['x', 'y', 'z', 'intensity', 'ring', 'time'])
            rings = set()
            for x, y, z, ring in point_cloud2.read_points(cloud, ('x', 'y', 'z', 'ring')):
                # Nominal geometry has no per-laser offsets: every return is 10 m away.
                self.assertAlmostEqual(math.sqrt(x * x + y * y + z * z), 10.0, delta=0.01)
                rings.add(ring)
            self.assertTrue(rings <= set(range(64)))
            self.assertEqual(len(rings), 63)  # one laser never returns
        os.remove(bag_path)


if __name__ == '__main__':
    rospy.init_node('bag_velodyne_msgs_test')
    rostest.rosrun('urban_detection', 'bag_velodyne_msgs', BagWithVelodyneMsgsType)

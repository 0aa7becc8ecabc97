#!/usr/bin/env python3
"""`roslaunch urban_detection pcap.launch pcap:=FILE` on a capture written here byte by byte
(hdl64e_packets.py): the partial revolutions at both ends are dropped, each whole revolution
becomes one cloud with every return decoded, and the cloud stamps keep the recorded spacing."""
import math
import os
import signal
import subprocess
import tempfile
import threading
import time
import unittest

import rospy
import rostest
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointCloud2

from hdl64e_packets import POINTS_PER_PACKET, make_packet, write_pcap

PACKETS_PER_REVOLUTION = 60          # 6 deg per packet
PACKET_PERIOD_S = 0.1 / PACKETS_PER_REVOLUTION
WHOLE_REVOLUTIONS = 3
T0 = 1700000000.0


class PcapLaunch(unittest.TestCase):
    def setUp(self):
        self.clouds = []
        self.lock = threading.Lock()

    def on_cloud(self, msg):
        with self.lock:
            self.clouds.append(msg)

    def test_replay_through_the_launch_file(self):
        # 10 packets of a partial revolution (300.5 .. 354.5 deg), three whole ones from 0.5 deg,
        # and the first packet of the next one.
        azimuths = [300.5 + 6 * i for i in range(10)]
        azimuths += [(0.5 + 6 * i) % 360 for i in range(WHOLE_REVOLUTIONS * PACKETS_PER_REVOLUTION + 1)]
        records = [(make_packet(az, i * 278), T0 + i * PACKET_PERIOD_S)
                   for i, az in enumerate(azimuths)]
        path = os.path.join(tempfile.mkdtemp(), 'drive.pcap')
        write_pcap(path, records)

        sub = rospy.Subscriber('/velodyne_points', PointCloud2, self.on_cloud, queue_size=10)
        launch = subprocess.Popen(['roslaunch', 'urban_detection', 'pcap.launch',
                                   'pcap:=' + path, 'rate:=1.0'])
        try:
            end = time.time() + 40.0
            while time.time() < end and len(self.clouds) < WHOLE_REVOLUTIONS:
                time.sleep(0.05)
            time.sleep(0.5)  # nothing more may come: the trailing partial revolution is dropped
        finally:
            sub.unregister()
            launch.send_signal(signal.SIGINT)
            launch.wait(timeout=20)
            os.remove(path)

        with self.lock:
            clouds = list(self.clouds)
        self.assertEqual(len(clouds), WHOLE_REVOLUTIONS)
        for i, cloud in enumerate(clouds):
            self.assertEqual(cloud.header.frame_id, 'velodyne')
            self.assertEqual(cloud.width * cloud.height, PACKETS_PER_REVOLUTION * POINTS_PER_PACKET)
            times = []
            for x, y, z, t in point_cloud2.read_points(cloud, ('x', 'y', 'z', 'time')):
                self.assertAlmostEqual(math.sqrt(x * x + y * y + z * z), 10.0, delta=0.01)
                times.append(t)
            # Point times run from the revolution's first packet to its last (59 periods later).
            self.assertAlmostEqual(min(times), 0.0, delta=1e-6)
            self.assertGreaterEqual(max(times), 59 * PACKET_PERIOD_S)
            self.assertLess(max(times), 60 * PACKET_PERIOD_S)
            if i > 0:
                dt = (cloud.header.stamp - clouds[i - 1].header.stamp).to_sec()
                self.assertAlmostEqual(dt, 0.1, delta=1e-4)


if __name__ == '__main__':
    rospy.init_node('pcap_launch_test')
    rostest.rosrun('urban_detection', 'pcap_launch', PcapLaunch)

#!/usr/bin/env python3
"""`roslaunch urban_detection live.launch driver:=false` (a roslaunch subprocess on the rostest
master) fed with the simulated drive's VelodyneScans at 5 Hz, while this node publishes
malformed sensor_msgs/PointCloud2 clouds on velodyne_points, which GridSegmentation subscribes
with the pipeline's PCL type (so they are deserialised by the typed path):

  * data 1,000 bytes longer than row_step * height (crashed the manager through pcl_ros),
  * data shorter than row_step * height, point_step 0, a field defined twice, big-endian data,
    2,000,000 points (all processed without a word before),

each must be refused with its own ERROR on /rosout, turn GridSegmentation's /diagnostics status
to ERROR, produce no /objects (the malformed clouds carry a stamp of their own), and the
pipeline must go on: /objects of a revolution sent after each refusal arrive. The nodelet
manager keeps its pid and its RSS returns within 20 MB of its steady state.
"""
import os
import signal
import struct
import subprocess
import tempfile
import threading
import time
import unittest

import rosbag
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import PointCloud2, PointField
from urban_detection.msg import DetectedObjectArray, VelodyneScan
from ud_test_helpers import node_pid, tool

PKG = 'urban_detection'
RSS_SLACK_MB = 20.0
MARK_S = 1000  # [s] stamps of the malformed clouds: far before any revolution's stamp
WAIT_S = 15.0  # [s] for a refusal and for /objects after it (a loaded 2-core machine)




def rss_mb(pid):
    with open('/proc/%d/status' % pid) as f:
        for line in f:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError('no VmRSS for %d' % pid)


def xyzirt(n, index):
    """A sound XYZIRT cloud of n points, as velodyne_pointcloud lays it out (22-byte points)."""
    m = PointCloud2()
    m.header.frame_id = 'velodyne'
    m.header.stamp = rospy.Time(MARK_S + index)
    m.height, m.width = 1, n
    m.fields = [PointField(name, offset, datatype, 1) for name, offset, datatype in
                [('x', 0, PointField.FLOAT32), ('y', 4, PointField.FLOAT32),
                 ('z', 8, PointField.FLOAT32), ('intensity', 12, PointField.FLOAT32),
                 ('ring', 16, PointField.UINT16), ('time', 18, PointField.FLOAT32)]]
    m.point_step = 22
    m.row_step = 22 * n
    point = struct.pack('<ffffHf', 8.0, 1.0, -1.0, 10.0, 5, 0.0)
    m.data = point * n
    m.is_dense = True
    return m


def malformed_clouds():
    """(what the ERROR must name, the cloud)"""
    cases = []
    c = xyzirt(5000, 0)
    c.data += bytes(1000)
    cases.append(('data longer than row_step x height', c))
    c = xyzirt(5000, 1)
    c.data = c.data[:-22 * 10]
    cases.append(('data shorter than row_step x height', c))
    c = xyzirt(5000, 2)
    c.point_step = 0
    cases.append(('point_step 0', c))
    c = xyzirt(5000, 3)
    c.fields.append(PointField('x', 12, PointField.FLOAT32, 1))
    cases.append(("duplicate field: 'x' defined twice", c))
    c = xyzirt(5000, 4)
    c.is_bigendian = True
    cases.append(('big-endian data', c))
    c = xyzirt(1, 5)
    c.width = 2000000
    c.row_step = 22 * c.width
    c.data = bytes(c.row_step)
    cases.append(('too many points', c))
    return cases


class MalformedClouds(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        bag = os.path.join(cls.tmp.name, 'drive.bag')
        subprocess.check_call([tool('urban_detection_simulate'), '--revolutions', '10',
                               '--bag', bag], stdout=subprocess.DEVNULL)
        cls.scans = []
        with rosbag.Bag(bag) as b:
            for _, msg, _ in b.read_messages():
                if msg._type.endswith('VelodyneScan'):
                    cls.scans.append(msg)
        assert len(cls.scans) >= 5, len(cls.scans)

    def setUp(self):
        self.lock = threading.Lock()
        self.objects = []  # (wall time, header stamp)
        self.errors = []   # /rosout ERROR texts
        self.seg_errors = []  # GridSegmentation's ERROR summaries on /diagnostics
        self.stop = threading.Event()
        self.scan_pub = rospy.Publisher('/velodyne_packets', VelodyneScan, queue_size=5)
        self.cloud_pub = rospy.Publisher('/velodyne_points', PointCloud2, queue_size=1)
        self.subs = [
            rospy.Subscriber('/objects', DetectedObjectArray, self.on_objects, queue_size=50),
            rospy.Subscriber('/rosout', Log, self.on_log, queue_size=200),
            rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics,
                             queue_size=50)]
        self.launch = subprocess.Popen(['roslaunch', PKG, 'live.launch', 'driver:=false'])
        deadline = time.time() + 40.0
        while time.time() < deadline and (self.scan_pub.get_num_connections() == 0 or
                                          self.cloud_pub.get_num_connections() == 0):
            time.sleep(0.2)
        self.assertGreater(self.cloud_pub.get_num_connections(), 0,
                           'nothing subscribed velodyne_points')
        self.sender = threading.Thread(target=self.send_revolutions)
        self.sender.start()

    def tearDown(self):
        self.stop.set()
        self.sender.join()
        for s in self.subs:
            s.unregister()
        self.scan_pub.unregister()
        self.cloud_pub.unregister()
        self.launch.send_signal(signal.SIGINT)
        try:
            self.launch.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.launch.kill()

    def on_objects(self, msg):
        with self.lock:
            self.objects.append((time.time(), msg.header.stamp))

    def on_log(self, msg):
        if msg.level == Log.ERROR:
            with self.lock:
                self.errors.append(msg.msg)

    def on_diagnostics(self, msg):
        for s in msg.status:
            if 'grid_segmentation' in s.name and s.level == DiagnosticStatus.ERROR:
                with self.lock:
                    self.seg_errors.append(s.message)

    def send_revolutions(self):
        i = 0
        while not self.stop.is_set():
            scan = self.scans[i % len(self.scans)]
            i += 1
            scan.header.stamp = rospy.Time.now()
            self.scan_pub.publish(scan)
            time.sleep(0.2)

    def wait(self, condition, seconds):
        deadline = time.time() + seconds
        while time.time() < deadline and not condition():
            time.sleep(0.05)
        return condition()

    @staticmethod
    def rss(pid, pick):
        samples = []
        for _ in range(5):
            time.sleep(0.2)
            samples.append(rss_mb(pid))
        return pick(samples)

    def objects_after(self, wall):
        with self.lock:
            return [s for w, s in self.objects if w > wall and s.to_sec() > MARK_S + 100]

    def errors_with(self, text):
        with self.lock:
            return [e for e in self.errors if 'velodyne_points' in e and text in e]

    def test_each_malformed_cloud_is_refused_and_the_pipeline_goes_on(self):
        self.assertTrue(self.wait(lambda: len(self.objects) >= 10, 40.0),
                        'no /objects before the malformed clouds')
        manager = node_pid('/urban_detection_manager', '/malformed_clouds_test')
        self.assertIsNotNone(manager)
        steady_mb = self.rss(manager, max)

        for why, cloud in malformed_clouds():
            self.cloud_pub.publish(cloud)
            self.assertTrue(self.wait(lambda: self.errors_with(why), WAIT_S),
                            'no ERROR naming "%s"' % why)
            refused = time.time()
            self.assertTrue(self.wait(lambda: self.objects_after(refused), WAIT_S),
                            '/objects did not go on after "%s"' % why)
            self.assertEqual(node_pid('/urban_detection_manager', '/malformed_clouds_test'), manager,
                             'the manager died on "%s"' % why)
            rospy.loginfo('refused: %s', self.errors_with(why)[0])

        with self.lock:
            marked = [s for _, s in self.objects if s.to_sec() < MARK_S + 100]
            seg_errors = list(self.seg_errors)
        self.assertEqual(marked, [], 'a malformed cloud gave /objects')
        self.assertTrue(any('refusing input' in e for e in seg_errors),
                        'GridSegmentation never reported ERROR on /diagnostics')
        after_mb = self.rss(manager, min)
        rospy.loginfo('manager RSS: steady %.1f MB, after the malformed clouds %.1f MB',
                      steady_mb, after_mb)
        self.assertLess(after_mb - steady_mb, RSS_SLACK_MB)


if __name__ == '__main__':
    rospy.init_node('malformed_clouds_test')
    rostest.rosrun(PKG, 'malformed_clouds', MalformedClouds)

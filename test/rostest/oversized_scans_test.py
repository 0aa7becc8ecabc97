#!/usr/bin/env python3
"""`roslaunch urban_detection live.launch driver:=false` (a roslaunch subprocess on the rostest
master) fed by this node with the simulated drive's VelodyneScans at 10 Hz over TCP, while

  * a second process publishes three VelodyneScans of 100,000 packets (120 MB each, 48 times a
    revolution) on the same topic: PacketToCloud refuses them (rejected_inputs on /diagnostics),
    /objects goes on (it comes within 1 s of their refusal) and the nodelet manager's RSS is back
    within 20 MB of its steady state;
  * a loader is killed with SIGKILL (no unload call; its bond breaks): the manager unloads its
    nodelet, the launch file respawns the loader, it loads the nodelet again, /objects resumes.

Run as `oversized_scans_test.py --huge N` it is the second process: N oversized scans, then it
waits for the subscriber to have them.
"""
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import rosbag
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from nodelet.srv import NodeletList
from urban_detection.msg import DetectedObjectArray, VelodynePacket, VelodyneScan
from ud_test_helpers import node_pid, tool

PKG = 'urban_detection'
HUGE_PACKETS = 100000
HUGE_SCANS = 3
RSS_SLACK_MB = 20.0
# [s] the longest /objects gap allowed while the oversized scans arrive, on a loaded machine.
GAP_BOUND_S = 8.0




def rss_mb(pid):
    with open('/proc/%d/status' % pid) as f:
        for line in f:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError('no VmRSS for %d' % pid)


def publish_huge(count):
    rospy.init_node('huge_scans', anonymous=True)
    pub = rospy.Publisher('/velodyne_packets', VelodyneScan, queue_size=count)
    deadline = time.time() + 20.0
    while time.time() < deadline and pub.get_num_connections() == 0:
        time.sleep(0.1)
    packet = VelodynePacket(data=bytes(range(256)) * 4 + bytes(182))
    huge = VelodyneScan()
    huge.header.frame_id = 'velodyne'
    huge.packets = [packet] * HUGE_PACKETS
    for _ in range(count):
        huge.header.stamp = rospy.Time.now()
        pub.publish(huge)
    time.sleep(30.0)  # the parent kills this process once the scans were refused


class OversizedScans(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        bag = os.path.join(cls.tmp.name, 'drive.bag')
        subprocess.check_call([tool('urban_detection_simulate'), '--revolutions', '20',
                               '--bag', bag], stdout=subprocess.DEVNULL)
        cls.scans = []
        with rosbag.Bag(bag) as b:
            for _, msg, _ in b.read_messages():
                if msg._type.endswith('VelodyneScan'):
                    cls.scans.append(msg)
        assert len(cls.scans) >= 15, len(cls.scans)

    def setUp(self):
        self.lock = threading.Lock()
        self.objects = []  # (wall time, header stamp)
        self.rejected = 0
        self.stop = threading.Event()
        self.pub = rospy.Publisher('/velodyne_packets', VelodyneScan, queue_size=5)
        self.subs = [rospy.Subscriber('/objects', DetectedObjectArray, self.on_objects,
                                      queue_size=50),
                     rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diagnostics,
                                      queue_size=50)]
        self.launch = subprocess.Popen(['roslaunch', PKG, 'live.launch', 'driver:=false'])
        deadline = time.time() + 40.0
        while time.time() < deadline and self.pub.get_num_connections() == 0:
            time.sleep(0.2)
        self.assertGreater(self.pub.get_num_connections(), 0, 'nothing subscribed the packets')
        self.sender = threading.Thread(target=self.send_revolutions)
        self.sender.start()

    def tearDown(self):
        self.stop.set()
        self.sender.join()
        for s in self.subs:
            s.unregister()
        self.pub.unregister()
        self.launch.send_signal(signal.SIGINT)
        try:
            self.launch.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.launch.kill()

    def on_objects(self, msg):
        with self.lock:
            self.objects.append((time.time(), msg.header.stamp))

    def on_diagnostics(self, msg):
        for status in msg.status:
            if 'packet_to_cloud' in status.name:
                for kv in status.values:
                    if kv.key == 'rejected_inputs':
                        with self.lock:
                            self.rejected = max(self.rejected, int(kv.value))

    def send_revolutions(self):
        """The drive's scans at 10 Hz, restamped now, until stopped."""
        i = 0
        while not self.stop.is_set():
            scan = self.scans[i % len(self.scans)]
            i += 1
            scan.header.stamp = rospy.Time.now()
            self.pub.publish(scan)
            time.sleep(0.1)

    def objects_after(self, stamp):
        with self.lock:
            return [(w, s) for w, s in self.objects if s >= stamp]

    def wait(self, condition, seconds):
        deadline = time.time() + seconds
        while time.time() < deadline and not condition():
            time.sleep(0.05)
        return condition()

    def test_oversized_scans_then_a_killed_loader(self):
        self.assertTrue(self.wait(lambda: len(self.objects) > 30, 30.0),
                        'no /objects before the oversized scans')
        manager = node_pid('/urban_detection_manager', '/oversized_scans_test')
        self.assertIsNotNone(manager)
        steady = []
        for _ in range(10):
            time.sleep(0.3)
            steady.append(rss_mb(manager))
        steady_mb = max(steady)

        started = time.time()
        huge = subprocess.Popen([sys.executable, os.path.abspath(__file__), '--huge',
                                 str(HUGE_SCANS)])
        try:
            # PacketToCloud's subscriber queue may drop one of them before deserialising it.
            self.assertTrue(self.wait(lambda: self.rejected >= 1, 60.0),
                            'the oversized scans were not refused')
            # the last of them refused: the count on /diagnostics (1 Hz) stands still
            count, still = self.rejected, time.time()
            while time.time() < still + 2.5 and time.time() < started + 60.0:
                time.sleep(0.05)
                if self.rejected != count:
                    count, still = self.rejected, time.time()
            refused_wall, refused = time.time(), rospy.Time.now()
            # Objects of revolutions sent after the refusal (seen on /diagnostics) within 1 s.
            self.assertTrue(self.wait(lambda: self.objects_after(refused), 5.0))
            delay = self.objects_after(refused)[0][0] - refused_wall
            time.sleep(5.0)
        finally:
            huge.kill()
            huge.wait()
        with self.lock:
            received = [w for w, _ in self.objects if w >= started]
        gaps = [b - a for a, b in zip(received, received[1:])]
        rospy.loginfo('%d oversized scans refused; /objects %.2f s after the refusal was seen, '
                      'longest gap in /objects %.2f s', self.rejected, delay, max(gaps))
        # Time bounds for a loaded 2-core machine (`scripts/run test` beside other work): the
        # bounds tell a chain that goes on from one that stalled on the refused scans, not how
        # fast an idle machine is. A refusal that blocked the chain would hold /objects back for
        # the whole transfer of the remaining scans (tens of seconds); an idle machine shows
        # well under a second for both, a busy one up to ~3 s of gap.
        self.assertLess(delay, GAP_BOUND_S)
        # While 240-360 MB arrive and are refused the chain may drop revolutions (the subscriber
        # queue is short), but it never stops for long.
        self.assertLess(max(gaps), GAP_BOUND_S)
        # ~10 Hz went on (fewer while the remaining oversized scans arrive)
        self.assertGreater(len(self.objects_after(refused)), 30)
        after_mb = []
        for _ in range(10):
            time.sleep(0.3)
            after_mb.append(rss_mb(manager))
        rospy.loginfo('manager RSS: steady %.1f MB, after the oversized scans %.1f MB',
                      steady_mb, min(after_mb))
        self.assertLess(min(after_mb) - steady_mb, RSS_SLACK_MB)

        # A loader dies (SIGKILL: no unload call, the bond breaks only seconds later): the
        # launch file respawns it after 1 s and the respawned loader (load_nodelet.py) unloads
        # the dead one's nodelet and loads it again at the first try: the first new loader
        # process is the one that holds the nodelet (one that failed would exit at once and a
        # second pid would appear).
        loader = node_pid('/grid_segmentation', '/oversized_scans_test')
        self.assertIsNotNone(loader)
        listing = rospy.ServiceProxy('/urban_detection_manager/list', NodeletList)
        self.assertIn('/grid_segmentation', listing().nodelets)
        os.kill(loader, signal.SIGKILL)
        killed = time.time()
        reloaded_at = None
        respawned = []  # every loader pid seen after the kill, in order
        since = None
        while time.time() < killed + 60.0 and reloaded_at is None:
            time.sleep(0.1)
            pid = node_pid('/grid_segmentation', '/oversized_scans_test')
            if pid is None or pid == loader or not os.path.exists('/proc/%d' % pid):
                continue
            if not respawned or respawned[-1] != pid:
                respawned.append(pid)
                since = time.time()
            elif time.time() - since > 3.0 and '/grid_segmentation' in listing().nodelets:
                reloaded_at = rospy.Time.now()
        rospy.loginfo('loader killed: respawned loaders %s; the nodelet loaded again after %s s',
                      respawned, reloaded_at and round(reloaded_at.to_sec() - killed, 1))
        self.assertIsNotNone(reloaded_at, 'the nodelet was not loaded again')
        self.assertEqual(len(respawned), 1, 'a respawned loader failed before one loaded')
        self.assertTrue(self.wait(lambda: len(self.objects_after(reloaded_at)) >= 10, 10.0),
                        'no /objects after the loader was respawned')

if __name__ == '__main__':
    if '--huge' in sys.argv:
        publish_huge(int(sys.argv[sys.argv.index('--huge') + 1]))
    else:
        rospy.init_node('oversized_scans_test')
        rostest.rosrun(PKG, 'oversized_scans', OversizedScans)

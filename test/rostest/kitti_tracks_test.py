#!/usr/bin/env python3
"""Tracks on real drives never lie about their frame: bags written by
urban_detection_kitti_to_bag, played by bag.launch (tracking on, as shipped), /objects/tracked
read here.

  * KITTI raw drive_0048 (sweeps without poses): the bag has no /tf (no odom invented), every
    track array is in the sensor frame with velocities_relative set, and the tracker says so
    once on /rosout;
  * the same bag looping (loop:=true): every track array stays in odom, the tracker restarts
    once per loop with one INFO and nothing else;
  * SemanticKITTI sequence 00 (poses.txt, the vehicle drives about 7 m/s past parked cars):
    the tracks are in odom, not relative, and every confirmed track on a parked car (the
    nearest labelled parked car instance, `car` not `moving-car`, placed in odom with the
    bag's own transforms) is slower than 0.5 m/s.

Needs ../shared/data (UD_SHARED_DATA overrides); skips, saying so, when it is absent.
"""
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import numpy as np
import rosbag
import rospy
import rostest
from rosgraph_msgs.msg import Log
from urban_detection.msg import TrackedObjectArray
from ud_test_helpers import shared_data, tool

PKG = 'urban_detection'
PARKED_MAX_MPS = 0.5
SK_CAR, SK_MOVING_CAR = 10, 252
MIN_GT_POINTS = 30
MIN_HITS = 5  # a track's velocity is judged after this many detections




def matrix(t):
    """4x4 of a geometry_msgs/Transform."""
    x, y, z, w = t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w
    m = np.eye(4)
    m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    m[:3, 3] = [t.translation.x, t.translation.y, t.translation.z]
    return m


class KittiTracksTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory(prefix='ud_kitti_tracks_')
        self.tracks = []
        self.logs = []
        self.lock = threading.Lock()
        self.launch = None
        KittiTracksTest.current = self

    @classmethod
    def setUpClass(cls):
        # One subscription per topic for all tests (re-subscribing in rospy can miss messages).
        cls.current = None
        cls.subs = [rospy.Subscriber('/objects/tracked', TrackedObjectArray,
                                     lambda m: cls.current and cls.current.on_tracks(m),
                                     queue_size=50),
                    rospy.Subscriber('/rosout', Log,
                                     lambda m: cls.current and cls.current.on_log(m),
                                     queue_size=500)]

    def tearDown(self):
        KittiTracksTest.current = None
        self.stop()
        self.tmp.cleanup()

    def stop(self):
        if self.launch is not None and self.launch.poll() is None:
            self.launch.send_signal(signal.SIGINT)
            try:
                self.launch.wait(20)
            except subprocess.TimeoutExpired:
                self.launch.kill()
                self.launch.wait()

    def on_log(self, msg):
        with self.lock:
            self.logs.append(msg.msg)

    def logged(self, text):
        """How many /rosout messages so far contain `text`."""
        time.sleep(1.0)  # /rosout is asynchronous
        with self.lock:
            return sum(1 for m in self.logs if text in m)

    def said(self, *words):
        """The /rosout messages naming any of `words`, for a failure's message."""
        with self.lock:
            return '/rosout:\n' + '\n'.join(m for m in self.logs if any(w in m for w in words))

    def on_tracks(self, msg):
        with self.lock:
            self.tracks.append(msg)

    def play(self, bag, sweeps, *args):
        log = open(os.path.join(self.tmp.name, 'roslaunch.log'), 'w')
        self.launch_log = log.name
        self.launch = subprocess.Popen(['roslaunch', PKG, 'bag.launch', 'bag:=' + bag,
                                        'rate:=0.5', 'delay:=3'] + list(args),
                                       stdout=log, stderr=subprocess.STDOUT)
        deadline = time.time() + 90.0
        last_n, last_t = 0, time.time()
        while time.time() < deadline and self.launch.poll() is None:
            with self.lock:
                n = len(self.tracks)
            if n != last_n:
                last_n, last_t = n, time.time()
            if n >= sweeps or (n > 0 and time.time() - last_t > 8.0):
                break
            time.sleep(0.2)
        with self.lock:
            return list(self.tracks)

    def launch_tail(self):
        with open(self.launch_log) as f:
            return ''.join(f.readlines()[-30:])

    def bag_of(self, source, name, *args):
        bag = os.path.join(self.tmp.name, name)
        subprocess.check_call([tool('urban_detection_kitti_to_bag'), source, bag] + list(args),
                              stdout=subprocess.DEVNULL)
        return bag

    def test_without_poses_sensor_frame_relative(self):
        drive = os.path.join(shared_data(), 'kitti_raw', 'drive_0048')
        if not os.path.isdir(drive):
            self.skipTest('shared data not found: %s' % drive)
        bag = self.bag_of(drive, 'drive_0048.bag')
        with rosbag.Bag(bag) as b:
            topics = b.get_type_and_topic_info().topics
        self.assertNotIn('/tf', topics, 'kitti_to_bag invented an odometry')
        tracks = self.play(bag, 22)
        self.assertGreaterEqual(len(tracks), 15, 'roslaunch:\n' + self.launch_tail())
        self.assertEqual({t.header.frame_id for t in tracks}, {'velodyne'})
        self.assertTrue(all(t.velocities_relative for t in tracks))
        self.assertEqual(self.logged('tracking in the sensor frame'), 1)

    def test_looping_bag_restarts_once_per_loop(self):
        seq = os.path.join(shared_data(), 'semantic_kitti', 'sequences', '00')
        if not os.path.isdir(os.path.join(seq, 'velodyne')):
            self.skipTest('shared data not found: %s' % seq)
        bag = self.bag_of(os.path.join(seq, 'velodyne'), 'seq00_loop.bag')
        tracks = self.play(bag, 28, 'loop:=true')  # about three passes of 10 scans
        self.assertGreaterEqual(len(tracks), 22, 'roslaunch:\n' + self.launch_tail())
        # Every revolution in odom (no flip to the sensor frame while tf restarts), and one
        # INFO per loop, no other restart.
        self.assertEqual({t.header.frame_id for t in tracks}, {'odom'},
                         [(i, t.header.stamp.to_sec(), t.header.frame_id)
                          for i, t in enumerate(tracks) if t.header.frame_id != 'odom'])
        loops = sum(1 for a, b in zip(tracks, tracks[1:]) if b.header.stamp < a.header.stamp)
        self.assertGreaterEqual(loops, 1)
        # The bag plays on while this is checked: one more loop may have begun.
        said = self.said('tracker', 'tracks', 'tf', 'stamp')
        self.assertIn(self.logged('stamp went back'), (loops, loops + 1), said)
        self.assertEqual(self.logged('tracks restarted'), 0, said)
        self.assertEqual(self.logged('tracking in the sensor frame'), 0, said)
        # The ids of a new loop are new: a track never spans two loops.
        first_ids = {o.id for t in tracks[:5] for o in t.objects}
        last_ids = {o.id for t in tracks[-3:] for o in t.objects}
        self.assertFalse(first_ids & last_ids)

    def test_with_poses_parked_cars_still(self):
        seq = os.path.join(shared_data(), 'semantic_kitti', 'sequences', '00')
        if not os.path.isdir(os.path.join(seq, 'velodyne')):
            self.skipTest('shared data not found: %s' % seq)
        bag = self.bag_of(os.path.join(seq, 'velodyne'), 'seq00.bag')
        # Parked cars (>= MIN_GT_POINTS points) in odom, through the bag's own transforms.
        static = None
        odom_T_base = []
        with rosbag.Bag(bag) as b:
            for topic, msg, _ in b.read_messages(topics=['/tf', '/tf_static']):
                for t in msg.transforms:
                    if topic == '/tf_static':
                        static = matrix(t.transform)
                    else:
                        odom_T_base.append(matrix(t.transform))
        self.assertIsNotNone(static)
        self.assertEqual(len(odom_T_base), 10)
        parked = []  # per scan: list of centroids in odom
        for i in range(10):
            pts = np.fromfile(os.path.join(seq, 'velodyne', '%06d.bin' % i),
                              dtype=np.float32).reshape(-1, 4)
            lab = np.fromfile(os.path.join(seq, 'labels', '%06d.label' % i), dtype=np.uint32)
            sem, inst = lab & 0xffff, lab >> 16
            odom_T_velo = odom_T_base[i].dot(static)
            cs = []
            for k in np.unique(inst[(sem == SK_CAR) & (inst > 0)]):
                sel = (sem == SK_CAR) & (inst == k)
                if sel.sum() >= MIN_GT_POINTS:
                    c = pts[sel, :3].mean(axis=0)
                    cs.append(odom_T_velo.dot(np.append(c, 1.0))[:3])
            parked.append(np.array(cs))
        ego_mps = np.linalg.norm(odom_T_base[9][:3, 3] - odom_T_base[0][:3, 3]) / 0.9
        tracks = self.play(bag, 10)
        self.assertGreaterEqual(len(tracks), 8, 'roslaunch:\n' + self.launch_tail())
        self.assertEqual({t.header.frame_id for t in tracks}, {'odom'})
        self.assertFalse(any(t.velocities_relative for t in tracks))
        stamps = sorted({t.header.stamp.to_sec() for t in tracks})
        t0 = stamps[0] - (0.0 if len(stamps) == 10 else 0.1 * (10 - len(stamps)))
        speeds = {}  # track id -> speed at its last confirmed revolution on a parked car
        for a in tracks:
            scan = int(round((a.header.stamp.to_sec() - t0) / 0.1))
            if not 0 <= scan < 10 or len(parked[scan]) == 0:
                continue
            for o in a.objects:
                if o.state != o.CONFIRMED:
                    continue
                p = np.array([o.pose.position.x, o.pose.position.y, o.pose.position.z])
                d = np.linalg.norm(parked[scan][:, :2] - p[:2], axis=1)
                if d.min() < 1.5 and o.hits >= MIN_HITS:
                    speeds[o.id] = np.hypot(o.velocity.x, o.velocity.y)

        sys.stderr.write('seq 00 with poses: vehicle %.1f m/s, %d tracks on parked cars, '
                         'speeds %s\n' % (ego_mps, len(speeds),
                                          ' '.join('%.2f' % s for s in sorted(speeds.values()))))
        self.assertGreater(ego_mps, 5.0)
        self.assertGreaterEqual(len(speeds), 5, 'confirmed tracks on parked cars')
        # One second of driving: a few boxes still shift as the viewpoint changes (the centre
        # of the visible part moves along a car), but the typical parked car stands still,
        # and none moves at the vehicle's speed (what relative velocities would show).
        self.assertLess(float(np.median(list(speeds.values()))), PARKED_MAX_MPS)
        self.assertLess(max(speeds.values()), 0.3 * ego_mps)


if __name__ == '__main__':
    rospy.init_node('kitti_tracks_test')
    rostest.rosrun(PKG, 'kitti_tracks', KittiTracksTest)

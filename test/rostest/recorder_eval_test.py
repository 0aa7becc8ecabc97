#!/usr/bin/env python3
"""The ObjectRecorder's files are what other tools read, and a recorded run scores to the same
figures as `urban_detection_eval`'s own run on the same scans: SemanticKITTI sequence 00 (10
scans) -> urban_detection_kitti_to_bag -> bag.launch record:=DIR/00 (the shipped configuration
and classifier) -> `urban_detection_eval --detections DIR`, against `urban_detection_eval` with
the package's config files. Also checks the KITTI label lines and the CSV.

Needs ../shared/data (UD_SHARED_DATA overrides); skips, saying so, when it is absent.
"""
import csv
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import roslib.packages
import rospy
import rostest
from ud_test_helpers import shared_data, tool

PKG = 'urban_detection'
SCANS = 10




def evaluate(seq, *args):
    out = os.path.join(tempfile.mkdtemp(prefix='ud_rec_eval_'), 'eval.json')
    config = os.path.join(roslib.packages.get_pkg_dir(PKG), 'config')
    configs = []
    for name in ('segmentation', 'hierarchical_grid', 'classification'):
        configs += ['--config', os.path.join(config, name + '.yaml')]
    subprocess.check_call([tool('urban_detection_eval'), '--semantic-kitti', seq, '--json', out]
                          + configs + list(args), stdout=subprocess.DEVNULL)
    with open(out) as f:
        return json.load(f)


class RecorderEval(unittest.TestCase):
    def test_recorded_run_scores_like_the_eval(self):
        seq = os.path.join(shared_data(), 'semantic_kitti', 'sequences', '00')
        if not os.path.isdir(os.path.join(seq, 'velodyne')):
            self.skipTest('shared data not found: %s' % seq)
        tmp = tempfile.TemporaryDirectory(prefix='ud_recorder_')
        bag = os.path.join(tmp.name, 'seq00.bag')
        subprocess.check_call([tool('urban_detection_kitti_to_bag'),
                               os.path.join(seq, 'velodyne'), bag], stdout=subprocess.DEVNULL)
        record = os.path.join(tmp.name, 'run', '00')
        log_path = os.path.join(tmp.name, 'roslaunch.log')
        with open(log_path, 'w') as log:
            launch = subprocess.Popen(['roslaunch', PKG, 'bag.launch', 'bag:=' + bag,
                                       'rate:=0.5', 'delay:=3', 'tracking:=false',
                                       'record:=' + record], stdout=log, stderr=subprocess.STDOUT)
            try:
                deadline = time.time() + 90.0
                while time.time() < deadline and launch.poll() is None:
                    if os.path.isdir(record) and sum(
                            1 for n in os.listdir(record) if n.endswith('.label')) >= SCANS:
                        break
                    time.sleep(0.5)
                time.sleep(1.0)  # the last revolution's CSV lines
            finally:
                launch.send_signal(signal.SIGINT)
                try:
                    launch.wait(20)
                except subprocess.TimeoutExpired:
                    launch.kill()
        with open(log_path) as f:
            tail = ''.join(f.readlines()[-30:])
        labels = sorted(n for n in os.listdir(record) if n.endswith('.label')) \
            if os.path.isdir(record) else []
        self.assertEqual(labels, ['%06d.label' % i for i in range(SCANS)], tail)

        own = evaluate(seq)['overall']
        recorded = evaluate(seq, '--detections', os.path.dirname(record))['overall']
        sys.stderr.write('eval own run: F %.4f (NO %d MO %d FO %d); recorded run: F %.4f '
                         '(NO %d MO %d FO %d)\n' % (own['f_rate'], own['no'], own['mo'], own['fo'],
                                                    recorded['f_rate'], recorded['no'],
                                                    recorded['mo'], recorded['fo']))
        for key in ('no', 'mo', 'fo', 'tp', 'detections'):
            self.assertEqual(recorded[key], own[key], key)
        self.assertAlmostEqual(recorded['f_rate'], own['f_rate'], places=6)

        # KITTI label lines: 15 fields + score; the CSV: one line per object of each revolution.
        kitti = os.path.join(record, 'kitti', '000000.txt')
        with open(kitti) as f:
            lines = [l.split() for l in f if l.strip()]
        self.assertGreater(len(lines), 0)
        for fields in lines:
            self.assertEqual(len(fields), 16, fields)
            self.assertIn(fields[0], ('Car', 'Pedestrian', 'Cyclist', 'Misc', 'DontCare'))
            self.assertGreater(float(fields[10]), 0.0)  # length
        with open(os.path.join(record, 'objects.csv')) as f:
            rows = list(csv.DictReader(f))
        self.assertEqual(len(rows), own['detections'])
        self.assertEqual(sum(1 for r in rows if r['revolution'] == '0'), len(lines))
        tmp.cleanup()


if __name__ == '__main__':
    rospy.init_node('recorder_eval_test')
    rostest.rosrun(PKG, 'recorder_eval', RecorderEval)

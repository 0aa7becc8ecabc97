#!/usr/bin/env python3
"""The launch files' contract, read with `roslaunch --dump-params` and `roslaunch --nodes`."""
import os
import subprocess
import sys
import unittest

import rostest
import yaml

PKG = 'urban_detection'


def roslaunch(*args):
    env = dict(os.environ)
    env['PATH'] = '/usr/bin:' + env.get('PATH', '')
    p = subprocess.run(['roslaunch'] + list(args), stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, env=env, timeout=60, check=False)
    return p.returncode, p.stdout.decode('utf-8', 'replace')


def params(launch, *args):
    code, out = roslaunch('--dump-params', PKG, launch, *args)
    if code != 0:
        raise AssertionError('roslaunch --dump-params %s failed:\n%s' % (launch, out))
    return yaml.safe_load(out)


def nodes(launch, *args):
    code, out = roslaunch('--nodes', PKG, launch, *args)
    if code != 0:
        raise AssertionError('roslaunch --nodes %s failed:\n%s' % (launch, out))
    return set(line.strip() for line in out.splitlines() if line.startswith('/'))


def sections(p, node):
    """The first path element of every parameter of `node` (/node/section/key -> section)."""
    prefix = '/%s/' % node
    return set(k[len(prefix):].split('/')[0] for k in p if k.startswith(prefix))


# The launch files a user starts, with the arguments they need to load.
TOP_LEVEL = (('bag.launch', ['bag:=/tmp/x.bag']), ('demo.launch', []), ('live.launch', []),
             ('pcap.launch', ['pcap:=/tmp/x.pcap']), ('pipeline.launch', []))


class LaunchParams(unittest.TestCase):
    def test_each_stage_gets_only_its_own_sections(self):
        p = params('live.launch', 'detector:=both')
        self.assertEqual(sections(p, 'hierarchical_grid_detector') - {'thread_nice',
                                                                      'early_objects'},
                         {'hierarchical_grid', 'classifier', 'box_fitting'})
        self.assertEqual(sections(p, 'kdtree_detector') - {'thread_nice', 'thread_idle',
                                                           'best_effort', 'queue_size'},
                         {'kdtree', 'classifier', 'box_fitting'})
        # The early-objects chain segments on its own: the segmentation's section, only then.
        early = params('live.launch', 'early_objects:=true')
        self.assertIs(early['/hierarchical_grid_detector/early_objects'], True)
        self.assertEqual(sections(early, 'hierarchical_grid_detector') - {'thread_nice',
                                                                          'early_objects'},
                         {'hierarchical_grid', 'classifier', 'box_fitting', 'segmentation'})
        self.assertEqual(sections(p, 'object_markers'), {'markers'})
        self.assertEqual(sections(p, 'object_markers_kdtree'), {'markers'})
        self.assertLess(sum(1 for k in p if k.startswith('/hierarchical_grid_detector/')), 80)

    def test_loaders_respawn_and_the_manager_is_required(self):
        # A loader that dies (bond broken) is restarted and loads its nodelet again at the first
        # try (load_nodelet.py unloads the dead loader's nodelet first); a dead manager stops
        # the launch (roslaunch says so) instead of leaving idle loaders.
        import roslaunch.config
        import roslaunch.xmlloader
        import rospkg
        for launch, argv in (('live.launch', ['detector:=both']), ('demo.launch', []),
                             ('bag.launch', ['bag:=/tmp/x.bag', 'input:=points']),
                             ('bag.launch', ['bag:=/tmp/x.bag']),
                             ('pcap.launch', ['pcap:=/tmp/x.pcap'])):
            path = os.path.join(rospkg.RosPack().get_path(PKG), 'launch', launch)
            config = roslaunch.config.ROSLaunchConfig()
            roslaunch.xmlloader.XmlLoader().load(path, config, argv=argv, verbose=False)
            loaders = [n for n in config.nodes if n.args.strip().startswith('load')]
            for n in loaders:
                self.assertEqual((n.package, n.type), (PKG, 'load_nodelet.py'),
                                 '%s: %s is not loaded by load_nodelet.py' % (launch, n.name))
            managers = [n for n in config.nodes
                        if n.type == 'nodelet' and n.args.strip() == 'manager']
            self.assertGreaterEqual(len(loaders), 4, launch)
            for n in loaders:
                self.assertTrue(n.respawn, '%s: %s does not respawn' % (launch, n.name))
            self.assertEqual(len(managers), 1, launch)
            self.assertTrue(managers[0].required, launch)
            self.assertTrue(managers[0].required, launch)

    def test_live_stamps_never_follow_a_bags_sim_time(self):
        # Every launch that does not play a bag sets it false: a bag.launch before it leaves
        # it true on the master.
        self.assertIs(params('live.launch')['/use_sim_time'], False)
        self.assertIs(params('pcap.launch', 'pcap:=/tmp/x.pcap')['/use_sim_time'], False)
        self.assertIs(params('demo.launch')['/use_sim_time'], False)
        self.assertIs(params('pipeline.launch')['/use_sim_time'], False)
        self.assertIs(params('bag.launch', 'bag:=/tmp/x.bag')['/use_sim_time'], True)

    def test_top_level_launches_take_the_same_arguments(self):
        for launch, argv in TOP_LEVEL:
            code, out = roslaunch('--ros-args', PKG, launch)
            self.assertEqual(code, 0, out)
            names = set(line.split()[0].rstrip(':') for line in out.splitlines()
                        if line.startswith('  '))
            self.assertLessEqual({'tracking', 'tracking_frame', 'classifier', 'rviz'}, names,
                                 launch)
            self.assertIn('/object_tracker', nodes(launch, *argv))
            self.assertNotIn('/object_tracker', nodes(launch, 'tracking:=false', *argv))
            p = params(launch, 'tracking_frame:=map', *argv)
            self.assertEqual(p['/object_tracker/fixed_frame'], 'map', launch)
            self.assertIn('/object_export', nodes(launch, *argv))

    def test_live_arguments_reach_their_nodes(self):
        p = params('live.launch', 'num_worker_threads:=2', 'queue_size:=3',
                   'rcvbuf_bytes:=1048576', 'timestamp_first_packet:=true')
        self.assertEqual(p['/urban_detection_manager/num_worker_threads'], 2)
        self.assertEqual(p['/packet_source/queue_size'], 3)
        self.assertEqual(p['/packet_source/rcvbuf_bytes'], 1048576)
        self.assertIs(p['/packet_source/timestamp_first_packet'], True)
        self.assertEqual(params('live.launch', 'detector:=both')['/kdtree_detector/thread_nice'],
                         10)
        # Beside the hierarchical chain the baseline is best effort (its status says so); alone it
        # is the detector and falls behind like any other. SCHED_IDLE only when asked.
        both = params('live.launch', 'detector:=both')
        self.assertIs(both['/kdtree_detector/best_effort'], True)
        self.assertIs(both['/kdtree_detector/thread_idle'], False)
        self.assertIs(params('live.launch', 'detector:=kdtree')['/kdtree_detector/best_effort'],
                      False)
        self.assertIs(params('pipeline.launch', 'detector:=both', 'kdtree_idle:=true')[
            '/kdtree_detector/thread_idle'], True)

    def test_live_streams_unless_motion_compensated(self):
        streaming = nodes('live.launch')
        self.assertIn('/packet_source', streaming)
        self.assertNotIn('/packet_to_cloud', streaming)
        self.assertIs(params('live.launch')['/packet_source/decode'], True)
        compensated = nodes('live.launch', 'fixed_frame:=odom')
        self.assertIn('/packet_to_cloud', compensated)
        self.assertIs(params('live.launch', 'fixed_frame:=odom')['/packet_source/decode'], False)
        external = nodes('live.launch', 'driver:=false')
        self.assertIn('/packet_to_cloud', external)
        self.assertNotIn('/packet_source', external)

    def test_a_mistyped_detector_is_one_clear_error(self):
        code, out = roslaunch('--nodes', PKG, 'live.launch', 'detector:=hierarchcal')
        self.assertNotEqual(code, 0)
        self.assertIn('detector:=hierarchcal is not one of hierarchical, kdtree, both', out)
        self.assertNotIn('Traceback', out)

    def test_a_bag_of_clouds_never_starts_packet_to_cloud(self):
        points = nodes('bag.launch', 'bag:=/tmp/x.bag', 'input:=points')
        self.assertIn('/cloud_input', points)
        self.assertNotIn('/packet_to_cloud', points)
        packets = nodes('bag.launch', 'bag:=/tmp/x.bag', 'input:=packets')
        self.assertIn('/packet_to_cloud', packets)
        self.assertNotIn('/cloud_input', packets)
        # auto: both loaders wait for bag_play.py's choice; only the one the bag needs loads
        # (the other removes its parameters; exercised end to end by launch_bag_points /
        # launch_bag_packets).
        import roslaunch.config
        import roslaunch.xmlloader
        import rospkg
        path = os.path.join(rospkg.RosPack().get_path(PKG), 'launch', 'bag.launch')
        config = roslaunch.config.ROSLaunchConfig()
        roslaunch.xmlloader.XmlLoader().load(path, config, argv=['bag:=/tmp/x.bag'],
                                             verbose=False)
        waiting = {n.name: n.args.split() for n in config.nodes
                   if n.name in ('packet_to_cloud', 'cloud_input')}
        self.assertEqual(waiting['packet_to_cloud'][-2:], ['--when-bag-input', 'packets'])
        self.assertEqual(waiting['cloud_input'][-2:], ['--when-bag-input', 'points'])


if __name__ == '__main__':
    rostest.rosrun(PKG, 'launch_params', LaunchParams, sys.argv)

#!/usr/bin/env python3
"""bag.launch's player: decides which of a bag's topics feed the pipeline, then execs
`rosbag play --clock` on them (same process, so roslaunch's signals reach rosbag directly).

input auto: the packets topic when the bag has it (its clouds, if also recorded, are not
played: the pipeline decodes its own), else the points topic. The chosen topic is remapped to
/velodyne_packets (decoded by PacketToCloud) or /points_in (sensor_msgs/PointCloud2, converted
by CloudInput into the pipeline's cloud type on /velodyne_points); /tf, /tf_static and
/ground_truth are played when present. With --input auto it sets ~input_chosen (packets or
points) for bag.launch's two adapter loaders: only the one the bag needs loads its nodelet, so
a bag of clouds never starts a PacketToCloud that would wait for packets. A missing bag, an unreadable bag or a bag without the requested input
is one clear error.
"""
import argparse
import os
import sys

import rosbag
import rospy

PACKET_TYPES = ('urban_detection/VelodyneScan', 'velodyne_msgs/VelodyneScan')
POINTS_TYPES = ('sensor_msgs/PointCloud2',)


def absolute(topic):
    return topic if topic.startswith('/') else '/' + topic


def choose(topics, mode, packets_topic, points_topic):
    """topics: {name: type}. Returns (played input topic, its pipeline name) or raises ValueError."""
    have_packets = topics.get(packets_topic) in PACKET_TYPES
    have_points = topics.get(points_topic) in POINTS_TYPES
    if mode == 'packets' or (mode == 'auto' and have_packets):
        if not have_packets:
            raise ValueError('no packets topic %s of type %s' % (
                packets_topic, ' or '.join(PACKET_TYPES)))
        return packets_topic, '/velodyne_packets'
    if mode in ('points', 'auto'):
        if not have_points:
            raise ValueError('neither packets (%s) nor clouds (%s, sensor_msgs/PointCloud2)'
                             % (packets_topic, points_topic) if mode == 'auto' else
                             'no sensor_msgs/PointCloud2 topic %s' % points_topic)
        return points_topic, '/points_in'
    raise ValueError('input must be auto, packets or points, not %r' % mode)


INPUT_KIND = {'/velodyne_packets': 'packets', '/points_in': 'points'}


def announce_input(target, fail):
    """Sets ~input_chosen (packets | points): bag.launch's two adapter loaders wait for it; the
    one the bag needs loads its nodelet, the other removes its parameters and idles."""
    import rosgraph  # only needed here
    import rosgraph.names
    name = rosgraph.names.ns_join(rosgraph.names.get_ros_namespace(argv=sys.argv),
                                  rosgraph.names.load_mappings(sys.argv).get('__name', 'rosbag_play'))
    try:
        rosgraph.Master(name).setParam(name + '/input_chosen', INPUT_KIND[target])
    except Exception as e:  # the master's socket errors come in several types
        fail('cannot set rosbag_play/input_chosen on the master: %s' % e)
    sys.stdout.write('[bag_play] input %s\n' % INPUT_KIND[target])


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('--bag', default='')
    parser.add_argument('--input', default='auto')
    parser.add_argument('--packets-topic', default='velodyne_packets')
    parser.add_argument('--points-topic', default='velodyne_points')
    parser.add_argument('--rate', type=float, default=1.0)
    parser.add_argument('--start', type=float, default=0.0)
    parser.add_argument('--delay', type=float, default=2.0)
    parser.add_argument('--loop', default='false')
    args, _ = parser.parse_known_args(rospy.myargv(argv)[1:])
    ros_args = [a for a in argv[1:] if ':=' in a]  # __name, __log from roslaunch

    def fail(message):
        sys.stderr.write('[bag_play] %s\n' % message)
        sys.exit(1)

    if not args.bag:
        fail('no bag given: roslaunch urban_detection bag.launch bag:=/path/drive.bag')
    if not os.path.isfile(args.bag):
        fail('bag %s does not exist' % args.bag)
    if not args.rate > 0:
        fail('rate must be > 0, not %g' % args.rate)
    try:
        with rosbag.Bag(args.bag) as bag:
            info = bag.get_type_and_topic_info().topics
    except Exception as e:  # rosbag raises several unrelated types for damaged files
        fail('cannot read bag %s: %s' % (args.bag, e))
    # A bag written by a C++ tool may store relative names; rosbag play resolves them in /.
    topics = {absolute(name): t.msg_type for name, t in info.items()}
    stored = {absolute(name): name for name in info}
    try:
        source, target = choose(topics, args.input, absolute(args.packets_topic),
                                absolute(args.points_topic))
    except ValueError as e:
        fail('%s: %s; its topics: %s' % (args.bag, e, ', '.join(
            '%s (%s)' % kv for kv in sorted(topics.items())) or 'none'))
    if args.input == 'auto':
        announce_input(target, fail)
    played = [stored[t] for t in [source] + ['/tf', '/tf_static', '/ground_truth'] if t in topics]
    command = ['rosbag', 'play', '--clock', '--rate', str(args.rate), '--start', str(args.start),
               '--delay', str(args.delay)]
    if args.loop.lower() in ('true', '1', 'yes'):
        command.append('--loop')
    command.append(args.bag)
    if source != target:
        command.append('%s:=%s' % (source, target))
    # rosbag's --topics takes every following word up to the next option: keep it last.
    command += ros_args + ['--topics'] + played
    sys.stdout.write('[bag_play] %s: playing %s as %s (%s)\n' % (
        args.bag, source, target, topics[source]))
    sys.stdout.flush()
    os.execvp(command[0], command)


if __name__ == '__main__':
    main(sys.argv)

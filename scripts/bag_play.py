#!/usr/bin/env python3
"""bag.launch's player: decides which of a bag's topics feed the pipeline, then execs
`rosbag play --clock` on them (same process, so roslaunch's signals reach rosbag directly).

input auto: the packets topic when the bag has it (its clouds, if also recorded, are not
played: the pipeline decodes its own), else the points topic. The chosen topic is remapped to
/velodyne_packets (decoded by PacketToCloud) or /points_in (sensor_msgs/PointCloud2, converted
by CloudInput into the pipeline's cloud type on /velodyne_points); /tf, /tf_static and
/ground_truth are played when present. With --manager (bag.launch's input:=auto), the one
adapter the bag needs is loaded into that nodelet manager here, once the bag is known, with the
parameters bag.launch put in its namespace: a bag of clouds never starts a PacketToCloud that
would wait for packets. A missing bag, an unreadable bag or a bag without the requested input
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


ADAPTERS = {'/velodyne_packets': ('packet_to_cloud', 'urban_detection/PacketToCloud'),
            '/points_in': ('cloud_input', 'urban_detection/CloudInput')}


def load_adapter(manager, target, fail):
    """Loads the nodelet that turns `target` into velodyne_points into `manager` (no bond: it
    lives as long as the manager)."""
    from nodelet.srv import NodeletLoad  # only needed here
    name, nodelet_type = ADAPTERS[target]
    service = '%s/load_nodelet' % absolute(manager)
    try:
        rospy.wait_for_service(service, timeout=30.0)
        ok = rospy.ServiceProxy(service, NodeletLoad)(
            name=absolute(name), type=nodelet_type, remap_source_args=[], remap_target_args=[],
            my_argv=[], bond_id='').success
    except (rospy.ROSException, rospy.ServiceException) as e:
        fail('cannot load %s into %s: %s' % (nodelet_type, manager, e))
    if not ok:
        fail('the manager %s refused to load %s (see its log)' % (manager, nodelet_type))
    sys.stdout.write('[bag_play] loaded %s as %s into %s\n' % (nodelet_type, absolute(name), manager))


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
    parser.add_argument('--manager', default='',
                        help='load the adapter the bag needs into this nodelet manager')
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
    if args.manager:
        load_adapter(args.manager, target, fail)
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

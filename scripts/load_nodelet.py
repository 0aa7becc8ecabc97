#!/usr/bin/env python3
"""`nodelet load TYPE MANAGER ...` that loads its nodelet at the first try after a respawn.

The launch files run every nodelet's loader with respawn="true". A loader that dies without
unloading its nodelet (SIGKILL, OOM killer) leaves the nodelet in the manager until the manager
notices the broken bond, seconds later; a loader respawned meanwhile gets "Cannot load nodelet
... exists", exits and is respawned again. This wrapper first asks the manager to unload a
nodelet of its own name (the dead loader's: ROS node names are unique, so no live loader holds
it), then replaces itself with `nodelet load` and the same arguments. On a first start the
manager does not list the name (or is not up yet) and nothing is unloaded.

`--when-bag-input packets|points` (bag.launch's input:=auto): first wait until bag_play.py has
read the bag and set /rosbag_play/input_chosen; when it names another input, remove this
loader's parameters (no stray settings of an adapter that never runs) and idle until shutdown
instead of loading.
"""
import os
import sys
import time

import rosgraph
import rosgraph.names
import roslib.packages
import rospy
from nodelet.srv import NodeletList, NodeletUnload


def main():
    args = rospy.myargv(sys.argv)  # without the __name:= ... remappings
    if len(args) < 4 or args[1] != 'load':
        sys.stderr.write('usage: load_nodelet.py load TYPE MANAGER [args]\n')
        return 2
    mappings = rosgraph.names.load_mappings(sys.argv)
    namespace = rosgraph.names.get_ros_namespace(argv=sys.argv)
    name = rosgraph.names.ns_join(namespace, mappings.get('__name', 'nodelet'))
    manager = rosgraph.names.ns_join(namespace, args[3]) if not args[3].startswith('/') else args[3]
    try:
        rospy.wait_for_service(manager + '/list', timeout=0.5)
        if name in rospy.ServiceProxy(manager + '/list', NodeletList)().nodelets:
            rospy.ServiceProxy(manager + '/unload_nodelet', NodeletUnload)(name=name)
    except (rospy.ROSException, rospy.ServiceException, OSError):
        pass  # no manager yet: a first start
    argv = sys.argv[1:]
    if '--when-bag-input' in argv:
        i = argv.index('--when-bag-input')
        wanted = argv[i + 1] if i + 1 < len(argv) else ''
        del argv[i:i + 2]
        if not wait_for_bag_input(name, wanted):
            return 0
    nodelet = roslib.packages.find_node('nodelet', 'nodelet')[0]
    os.execv(nodelet, [nodelet] + argv)


def wait_for_bag_input(name, wanted):
    """True when bag_play.py chose `wanted`; else removes `name`'s parameters and idles (the
    loader is respawned by roslaunch whenever it exits) until interrupted: False."""
    master = rosgraph.Master(name)
    chosen = ''
    while not chosen:
        try:
            chosen = master.getParam('/rosbag_play/input_chosen')
        except Exception:  # not set yet, or the master is starting
            chosen = ''
        if not chosen:
            time.sleep(0.2)
    if chosen == wanted:
        return True
    try:
        master.deleteParam(name)
    except Exception:
        pass  # it had none
    sys.stdout.write('[%s] the bag has %s: not loaded\n' % (name, chosen))
    sys.stdout.flush()
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        return False


if __name__ == '__main__':
    sys.exit(main())

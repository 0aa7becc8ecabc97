#!/usr/bin/env python3
"""`scripts/run setup` installs everything the documented command-line use needs.

Checked with the system interpreter (/usr/bin/python3, the one Debian's ROS tools run with),
each import in a fresh process so that nothing this test imported itself hides a gap:
  * the Python message module of every package whose messages the project publishes or
    subscribes (`rostopic hz /objects/markers`, `rostopic echo /diagnostics`, ... need it to
    load the message class), the package's own messages included;
  * the modules behind rostopic, rosservice, rosbag, roslaunch and dynparam;
  * every name in APT_PACKAGES of scripts/run is a Debian package apt knows, and the Python
    ROS packages the tools above come from are listed there explicitly.
Needs the workspace environment for the package's own messages (catkin's run_tests provides it).
"""
import os
import re
import subprocess
import sys
import unittest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PYTHON = '/usr/bin/python3'

# Every message package on a topic of the pipeline, the launch files and the tools.
MESSAGE_MODULES = [
    'std_msgs.msg', 'geometry_msgs.msg', 'sensor_msgs.msg', 'visualization_msgs.msg',
    'diagnostic_msgs.msg', 'tf2_msgs.msg', 'rosgraph_msgs.msg', 'dynamic_reconfigure.msg',
    'dynamic_reconfigure.srv', 'urban_detection.msg', 'nodelet.srv',
]
# The Python side of the tools the README tells users to run.
TOOL_MODULES = ['rospy', 'rostopic', 'rosservice', 'rosbag', 'roslaunch', 'rosparam',
                'dynamic_reconfigure.client']
# Debian packages that must be named in APT_PACKAGES, not only pulled in by chance.
REQUIRED_APT = ['python3-rospy', 'python3-rostopic', 'python3-rosservice',
                'python3-dynamic-reconfigure', 'python3-std-msgs', 'python3-geometry-msgs',
                'python3-sensor-msgs', 'python3-visualization-msgs', 'python3-diagnostic-msgs',
                'python3-tf2-msgs', 'python3-rosbag', 'python3-nodelet']


def apt_packages():
    """The APT_PACKAGES array of scripts/run (comments and line breaks allowed)."""
    with open(os.path.join(REPO, 'scripts', 'run')) as f:
        text = f.read()
    match = re.search(r'^APT_PACKAGES=\((.*?)^\)', text, re.S | re.M)
    if not match:
        raise AssertionError('no APT_PACKAGES=( ... ) in scripts/run')
    body = '\n'.join(line.split('#', 1)[0] for line in match.group(1).splitlines())
    return body.split()


def import_error(module):
    """'' when `module` imports in a fresh /usr/bin/python3, else the interpreter's error."""
    proc = subprocess.run([PYTHON, '-c', 'import %s' % module], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, universal_newlines=True, timeout=60)
    return '' if proc.returncode == 0 else proc.stdout.strip().splitlines()[-1]


class SetupPackages(unittest.TestCase):
    def test_message_modules_import(self):
        errors = {m: import_error(m) for m in MESSAGE_MODULES}
        self.assertEqual({m: e for m, e in errors.items() if e}, {})

    def test_tool_modules_import(self):
        errors = {m: import_error(m) for m in TOOL_MODULES}
        self.assertEqual({m: e for m, e in errors.items() if e}, {})

    def test_python_ros_packages_are_listed(self):
        listed = set(apt_packages())
        self.assertEqual([p for p in REQUIRED_APT if p not in listed], [])

    def test_every_listed_package_exists(self):
        packages = apt_packages()
        self.assertGreater(len(packages), 10)
        self.assertEqual(len(packages), len(set(packages)), 'a package is listed twice')
        unknown = []
        for p in packages:
            installed = subprocess.run(['dpkg-query', '-W', '-f=${Status}', p],
                                       stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                       universal_newlines=True)
            if 'install ok installed' in installed.stdout:
                continue
            policy = subprocess.run(['apt-cache', 'policy', p], stdout=subprocess.PIPE,
                                    stderr=subprocess.DEVNULL, universal_newlines=True)
            candidate = re.search(r'Candidate:\s*(\S+)', policy.stdout)
            if not candidate or candidate.group(1) == '(none)':
                unknown.append(p)
        self.assertEqual(unknown, [], 'not installed and unknown to apt')


if __name__ == '__main__':
    import rosunit
    rosunit.unitrun('urban_detection', 'setup_packages', SetupPackages)

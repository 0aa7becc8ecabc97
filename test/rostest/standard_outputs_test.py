#!/usr/bin/env python3
"""A subscriber of the standard type receives the objects: the message class is generated
with genpy from vision_msgs' ROS 1 definition text (as a bag or a vision_msgs build carries it,
type name vision_msgs/Detection3DArray), not from this package's .msg files. Its MD5 must be
the one vision_msgs publishes and this package's Detection3DArray's; ObjectExport's output
must reach it over the wire with each object's class, score and box.
"""
import math
import threading
import time
import unittest

import genpy.dynamic
import rospy
import rostest
from geometry_msgs.msg import PoseWithCovariance, Vector3
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import Header
from urban_detection.msg import DetectedObject, DetectedObjectArray, Detection3DArray

# vision_msgs' published MD5 of Detection3DArray (ROS 1 noetic).
VISION_MSGS_MD5 = '05c51d9aea1fb4cfdc8effb94f197b6f'
SEP = '=' * 80 + '\n'
DETECTION3D_ARRAY = """# A list of 3D detections, for a multi-object 3D detector.

Header header

# A list of the detected proposals. A multi-proposal detector might generate
#   this list with many candidate detections generated from a single input.
Detection3D[] detections
"""
DETECTION3D = """# Defines a 3D detection result.
#
# This extends a basic 3D classification by including position information,
#   allowing a classification result for a specific position in an image to
#   to be located in the larger image.

Header header

# Class probabilities. Does not have to include hypotheses for all possible
#   object ids, the scores for any ids not listed are assumed to be 0.
ObjectHypothesisWithPose[] results

# 3D bounding box surrounding the object.
BoundingBox3D bbox

# The 3D data that generated these results (i.e. region proposal cropped out of
#   the image). This information is not required for all detectors, so it may
#   be empty.
sensor_msgs/PointCloud2 source_cloud
"""
OBJECT_HYPOTHESIS_WITH_POSE = """# An object hypothesis that contains position information.

# The unique numeric ID of object detected. To get additional information about
#   this ID, such as its human-readable name, listeners should perform a lookup
#   in a metadata database. See vision_msgs/VisionInfo.msg for more detail.
int64 id

# The probability or confidence value of the detected object. By convention,
#   this value should lie in the range [0-1].
float64 score

# The 6D pose of the object hypothesis. This pose should be
#   defined as the pose of some fixed reference point on the object, such a
#   the geometric center of the bounding box or the center of mass of the
#   object.
# Note that this pose is not stamped; frame information can be defined by
#   parent messages.
# Also note that different classes predicted for the same input data may have
#   different predicted 6D poses.
geometry_msgs/PoseWithCovariance pose
"""
BOUNDING_BOX_3D = """# A 3D bounding box that can be positioned and rotated about its center (6 DOF)
# Dimensions of this box are in meters, and as such, it may be migrated to
#   another package, such as geometry_msgs, in the future.

# The 3D position and orientation of the bounding box center
geometry_msgs/Pose center

# The size of the bounding box, in meters, surrounding the object's center
#   pose.
geometry_msgs/Vector3 size
"""


def vision_msgs_class():
    """vision_msgs/Detection3DArray generated from its definition text (dependencies of the
    standard packages from their installed definitions, as a bag's connection header)."""
    parts = [DETECTION3D_ARRAY]
    for name, text in (('vision_msgs/Detection3D', DETECTION3D),
                       ('vision_msgs/ObjectHypothesisWithPose', OBJECT_HYPOTHESIS_WITH_POSE),
                       ('vision_msgs/BoundingBox3D', BOUNDING_BOX_3D),
                       ('std_msgs/Header', Header._full_text)):
        parts.append(SEP + 'MSG: ' + name + '\n' + text)
    # Their own full texts carry their dependencies (Pose, Point, Quaternion, PointField).
    for cls in (PoseWithCovariance, Vector3, PointCloud2):
        parts.append(SEP + 'MSG: ' + cls._type + '\n' + cls._full_text)
    return genpy.dynamic.generate_dynamic('vision_msgs/Detection3DArray',
                                          '\n'.join(parts))['vision_msgs/Detection3DArray']


def detected(i, x, label, confidence):
    o = DetectedObject()
    o.id = i
    o.point_count = 40
    o.obb_pose.position.x = x
    o.obb_pose.position.y = 2.0
    o.obb_pose.position.z = -0.9
    yaw = 0.3 * i
    o.obb_pose.orientation.z = math.sin(yaw / 2)
    o.obb_pose.orientation.w = math.cos(yaw / 2)
    o.obb_dimensions.x, o.obb_dimensions.y, o.obb_dimensions.z = 4.2, 1.8, 1.5
    o.class_label = label
    o.class_confidence = confidence
    return o


class StandardOutputs(unittest.TestCase):
    def test_vision_msgs_subscriber_receives_objects(self):
        cls = vision_msgs_class()
        self.assertEqual(cls._type, 'vision_msgs/Detection3DArray')
        self.assertEqual(cls._md5sum, VISION_MSGS_MD5)
        self.assertEqual(Detection3DArray._md5sum, VISION_MSGS_MD5)

        received = []
        lock = threading.Lock()

        def cb(msg):
            with lock:
                received.append(msg)
        sub = rospy.Subscriber('/objects/detections3d', cls, cb, queue_size=10)
        pub = rospy.Publisher('/objects', DetectedObjectArray, queue_size=10)
        # Lazy: ObjectExport subscribes to /objects once /objects/detections3d has a listener.
        deadline = time.time() + 20.0
        while pub.get_num_connections() == 0 and time.time() < deadline:
            time.sleep(0.1)
        self.assertGreater(pub.get_num_connections(), 0, 'ObjectExport did not subscribe')
        msg = DetectedObjectArray()
        msg.header.frame_id = 'velodyne'
        msg.detector = 'hierarchical_grid'
        msg.objects = [detected(1, 10.0, 'vehicle', 0.9), detected(2, -5.0, 'pedestrian', 0.7),
                       detected(3, 3.0, 'unknown', 0.0)]
        for k in range(5):
            msg.header.stamp = rospy.Time(100, k)
            pub.publish(msg)
            time.sleep(0.2)
            with lock:
                if received:
                    break
        with lock:
            self.assertTrue(received, 'nothing arrived on /objects/detections3d')
            out = received[0]
        self.assertIsInstance(out, cls)
        self.assertEqual(out.header.frame_id, 'velodyne')
        self.assertEqual(len(out.detections), 3)
        for d, o, class_id in zip(out.detections, msg.objects, (1, 2, 255)):
            self.assertEqual(d.header.frame_id, 'velodyne')
            self.assertEqual(len(d.results), 1)
            self.assertEqual(d.results[0].id, class_id)
            self.assertAlmostEqual(d.results[0].score, o.class_confidence, places=5)
            self.assertAlmostEqual(d.bbox.center.position.x, o.obb_pose.position.x)
            self.assertAlmostEqual(d.bbox.center.orientation.z, o.obb_pose.orientation.z)
            self.assertAlmostEqual(d.bbox.size.x, 4.2)
            self.assertAlmostEqual(d.results[0].pose.pose.position.y, 2.0)
        sub.unregister()


if __name__ == '__main__':
    rospy.init_node('standard_outputs_test')
    rostest.rosrun('urban_detection', 'standard_outputs', StandardOutputs)

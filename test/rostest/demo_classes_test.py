#!/usr/bin/env python3
"""The object classifier in demo.launch: over 30 revolutions of the simulated drive, every
published object has a class of the classifier (vehicle, pedestrian, cyclist, other_object) and
a confidence in (0, 1]; vehicles are found; the rejected objects are labelled non_object; each
object's box marker has its class colour (the palette of object_markers.cpp), its text (when
shown: not while the tracker labels the objects) names the class, and the legend lists the
classes in their colours."""
import threading
import time
import unittest

import rospy
import rostest
from urban_detection.msg import DetectedObjectArray
from visualization_msgs.msg import Marker, MarkerArray

PKG = 'urban_detection'
OBJECT_CLASSES = {'vehicle', 'pedestrian', 'cyclist', 'other_object'}
# RGB of the classes in object_markers.cpp's palette.
CLASS_RGB = {'vehicle': (40, 150, 255), 'pedestrian': (255, 70, 110), 'cyclist': (255, 210, 0),
             'other_object': (0, 230, 200)}
REVOLUTIONS = 30


class DemoClasses(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.objects, self.rejected, self.markers = [], [], []
        rospy.Subscriber('/objects', DetectedObjectArray, self.keep(self.objects), queue_size=50)
        rospy.Subscriber('/objects/rejected', DetectedObjectArray, self.keep(self.rejected),
                         queue_size=50)
        rospy.Subscriber('/objects/markers', MarkerArray, self.keep(self.markers), queue_size=50)

    def keep(self, store):
        def cb(msg):
            with self.lock:
                store.append(msg)
        return cb

    def test_classes_and_markers(self):
        deadline = time.time() + 120.0
        while time.time() < deadline and not rospy.is_shutdown():
            with self.lock:
                if min(len(self.objects), len(self.rejected), len(self.markers)) >= REVOLUTIONS:
                    break
            time.sleep(0.2)
        with self.lock:
            objects, rejected, markers = list(self.objects), list(self.rejected), list(self.markers)
        self.assertGreaterEqual(len(objects), REVOLUTIONS, 'objects messages')
        self.assertGreaterEqual(len(rejected), REVOLUTIONS, 'objects/rejected messages')
        self.assertGreaterEqual(len(markers), REVOLUTIONS, 'marker messages')

        counts = {}
        for msg in objects:
            for o in msg.objects:
                self.assertIn(o.class_label, OBJECT_CLASSES)
                self.assertGreater(o.class_confidence, 0.0)
                self.assertLessEqual(o.class_confidence, 1.0)
                counts[o.class_label] = counts.get(o.class_label, 0) + 1
        # The drive has parked and moving cars in view all along.
        self.assertGreater(counts.get('vehicle', 0), 2 * len(objects), counts)
        # The drive's hedges, bushes and verges: rejected as non-objects.
        n_rejected = sum(len(m.objects) for m in rejected)
        self.assertGreater(n_rejected, len(rejected), 'rejected objects per revolution')
        for msg in rejected:
            for o in msg.objects:
                self.assertEqual(o.class_label, 'non_object')

        # Markers: the newest array of each revolution matches its objects by id.
        by_stamp = {m.header.stamp: m for m in objects}
        checked = 0
        for arr in markers:
            boxes = [m for m in arr.markers if m.ns == 'objects' and m.action == Marker.ADD]
            texts = {m.id: m for m in arr.markers if m.ns == 'object_ids'}
            # The legend: each class name in its class colour.
            legend = {m.text: m for m in arr.markers if m.ns == 'legend'}
            self.assertEqual(set(legend), OBJECT_CLASSES)
            for name, m in legend.items():
                rgb = tuple(int(round(255 * c)) for c in (m.color.r, m.color.g, m.color.b))
                self.assertEqual(rgb, CLASS_RGB[name], 'legend entry %s' % name)
            if not boxes:
                continue
            msg = by_stamp.get(boxes[0].header.stamp)
            if msg is None:
                continue
            label_of = {o.id: o.class_label for o in msg.objects}
            for b in boxes:
                label = label_of[b.id]
                rgb = tuple(int(round(255 * c)) for c in (b.color.r, b.color.g, b.color.b))
                self.assertEqual(rgb, CLASS_RGB[label], 'box of a %s' % label)
                text = texts.get(b.id)
                if text is not None:
                    self.assertIn(label, text.text)
                checked += 1
        self.assertGreater(checked, 20, 'boxes checked against their objects')


if __name__ == '__main__':
    rospy.init_node('demo_classes_test')
    rostest.rosrun(PKG, 'demo_classes', DemoClasses)

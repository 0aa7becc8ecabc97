#!/usr/bin/env python3
"""scripts/soak_monitor.py's bookkeeping, without a pipeline: how header.seq values are
classified (a revolution delivered twice is a duplicate, not a second revolution), and the
bounds that make `scripts/run soak` fail (RSS growth, skipped revolutions, an output rate off
the sensor's in either direction, duplicates, a stepped wall clock)."""
import os
import sys
import unittest

import rostest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'scripts'))
import soak_monitor  # noqa: E402


def summary(rate_hz=10.0, rss=(90.0, 91.0), skipped_fraction=0.0, duplicates=0,
            clocks=(1800.0, 1800.0)):
    return {'rate_hz': rate_hz, 'rss_mb': {'start': rss[0], 'end': rss[1]},
            'skipped_fraction': skipped_fraction, 'duplicate_messages': duplicates,
            'clock_s': {'monotonic': clocks[0], 'wall': clocks[1]}}


def failures(s):
    return soak_monitor.check_bounds(s, max_rss_growth_mb=20.0, max_skipped_fraction=0.01,
                                     expected_rate_hz=10.0, rate_tolerance=0.05,
                                     max_clock_disagreement=0.01)


class SoakMonitorTest(unittest.TestCase):
    def test_classifies_next_gap_duplicate_and_restart(self):
        t = soak_monitor.SeqTracker(last_seq=9)
        self.assertEqual([t.add(s) for s in (10, 11, 14, 14, 15, 3, 4)],
                         ['next', 'next', 'gap', 'duplicate', 'next', 'restart', 'next'])
        self.assertEqual(t.distinct, 6)
        self.assertEqual(t.gaps, 2)
        self.assertEqual(t.duplicates, 1)
        self.assertEqual(t.restarts, 1)

    def test_every_revolution_twice_counts_once(self):
        # Two publishers of the same revolutions on one topic: twice the messages, same rate.
        t = soak_monitor.SeqTracker()
        for seq in range(1, 101):
            t.add(seq)
            t.add(seq)
        self.assertEqual((t.distinct, t.duplicates, t.gaps, t.restarts), (100, 100, 0, 0))

    def test_a_clean_run_passes(self):
        self.assertEqual(failures(summary(rate_hz=9.97)), [])

    def test_each_bound_fails_on_its_own(self):
        self.assertEqual(len(failures(summary(rate_hz=19.9))), 1)  # too fast is as wrong
        self.assertEqual(len(failures(summary(rate_hz=9.0))), 1)
        self.assertEqual(len(failures(summary(rss=(90.0, 111.0)))), 1)
        self.assertEqual(len(failures(summary(skipped_fraction=0.02))), 1)
        self.assertEqual(len(failures(summary(skipped_fraction=None))), 1)  # nothing received
        self.assertEqual(len(failures(summary(duplicates=3))), 1)
        self.assertIn('clock', failures(summary(clocks=(1800.0, 3600.0)))[0])

    def test_slope(self):
        samples = [(t, 90.0 + 0.001 * t) for t in range(0, 1800, 10)]
        self.assertAlmostEqual(soak_monitor.slope_per_hour(samples), 3.6, places=6)


if __name__ == '__main__':
    rostest.rosrun('urban_detection', 'soak_monitor', SoakMonitorTest)

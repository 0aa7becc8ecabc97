#!/usr/bin/env python3
"""Soak monitor (issue 8), run by scripts/soak.sh against a running demo.launch.

Measures, for `--minutes` after `--warmup` seconds:
  * latency of every /objects message: receive wall time - header.stamp (the stamp is the time
    of the revolution's FIRST packet, so the figure includes the ~100 ms the sensor takes to
    sweep the revolution at 600 rpm), p50 / p99 / max;
  * revolutions skipped end to end: gaps in header.seq (numbered by the sensor and passed on
    by every stage), plus the per-stage totals of skipped_revolutions on /diagnostics;
  * resident memory (VmRSS) of the nodelet manager process, sampled every 10 s: at the end of
    the warm-up and at the end; also the least-squares slope over the measured period;
  * WARN/ERROR statuses seen on /diagnostics.
Writes a JSON summary (--out) and prints it; exits 1 when a --max-* bound is exceeded.
"""
import argparse
import json
import re
import sys
import threading
import time
import xmlrpc.client

import rosgraph
import rospy
from diagnostic_msgs.msg import DiagnosticArray
from urban_detection.msg import DetectedObjectArray


def manager_pid(name):
    master = rosgraph.Master('/soak_monitor')
    uri = master.lookupNode(name)
    code, _, pid = xmlrpc.client.ServerProxy(uri).getPid('/soak_monitor')
    if code != 1:
        raise RuntimeError('cannot get the pid of %s' % name)
    return pid


def rss_mb(pid):
    with open('/proc/%d/status' % pid) as f:
        for line in f:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError('no VmRSS for pid %d' % pid)


def percentile(sorted_values, q):
    if not sorted_values:
        return float('nan')
    k = min(len(sorted_values) - 1, max(0, int(round(q * (len(sorted_values) - 1)))))
    return sorted_values[k]


class Monitor:
    def __init__(self):
        self.lock = threading.Lock()
        self.measuring = False
        self.latencies = []
        self.received = 0
        self.objects = 0
        self.first_seq = None
        self.last_seq = None
        self.seq_gaps = 0
        self.restarts = 0
        self.stage_skipped = {}
        self.warnings = {}

    def on_objects(self, msg):
        now = rospy.Time.now()
        with self.lock:
            if not self.measuring:
                self.last_seq = msg.header.seq
                return
            self.received += 1
            self.objects += len(msg.objects)
            self.latencies.append((now - msg.header.stamp).to_sec())
            seq = msg.header.seq
            if self.first_seq is None:
                self.first_seq = seq
            if self.last_seq is not None and seq > self.last_seq + 1:
                self.seq_gaps += seq - self.last_seq - 1
            elif self.last_seq is not None and seq <= self.last_seq:
                self.restarts += 1  # the looped drive restarts the numbering
            self.last_seq = seq

    def on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                values = {kv.key: kv.value for kv in status.values}
                if 'skipped_revolutions' in values:
                    self.stage_skipped[status.name] = int(values['skipped_revolutions'])
                if self.measuring and status.level >= 1:
                    # One entry per kind of warning: the figures in the message vary.
                    key = '%s: %s' % (status.name, re.sub(r'[0-9.]+', '#', status.message))
                    self.warnings[key] = self.warnings.get(key, 0) + 1


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('--minutes', type=float, default=30.0)
    parser.add_argument('--warmup', type=float, default=60.0, help='[s] before measuring')
    parser.add_argument('--manager', default='/urban_detection_manager')
    parser.add_argument('--out', required=True)
    parser.add_argument('--source', default='pcap', help='recorded in the summary')
    parser.add_argument('--max-rss-growth-mb', type=float, default=20.0)
    parser.add_argument('--max-skipped-fraction', type=float, default=0.01)
    parser.add_argument('--min-rate-hz', type=float, default=9.0)
    args = parser.parse_args(rospy.myargv(sys.argv)[1:])

    rospy.init_node('soak_monitor', disable_signals=True)
    mon = Monitor()
    rospy.Subscriber('/objects', DetectedObjectArray, mon.on_objects, queue_size=100,
                     tcp_nodelay=True)
    rospy.Subscriber('/diagnostics', DiagnosticArray, mon.on_diagnostics, queue_size=100)
    deadline = time.time() + 60.0
    pid = None
    while pid is None and time.time() < deadline:
        try:
            pid = manager_pid(args.manager)
        except Exception:
            time.sleep(1.0)
    if pid is None:
        print('soak: no nodelet manager %s' % args.manager, file=sys.stderr)
        return 2

    time.sleep(args.warmup)
    with mon.lock:
        mon.measuring = True
        skipped_start = dict(mon.stage_skipped)
    t0 = time.time()
    samples = [(0.0, rss_mb(pid))]
    end = t0 + 60.0 * args.minutes
    while time.time() < end:
        time.sleep(min(10.0, max(0.0, end - time.time())))
        samples.append((time.time() - t0, rss_mb(pid)))
    duration = time.time() - t0
    with mon.lock:
        mon.measuring = False
        lat = sorted(mon.latencies)
        received, gaps, restarts = mon.received, mon.seq_gaps, mon.restarts
        stage = {k: v - skipped_start.get(k, 0) for k, v in mon.stage_skipped.items()}
        warnings = dict(mon.warnings)
        objects = mon.objects
    n = len(samples)
    mt = sum(t for t, _ in samples) / n
    mr = sum(r for _, r in samples) / n
    var = sum((t - mt) ** 2 for t, _ in samples)
    slope = sum((t - mt) * (r - mr) for t, r in samples) / var if var > 0 else 0.0
    expected = received + gaps
    summary = {
        'minutes': round(duration / 60.0, 2),
        'source': args.source,
        'warmup_s': args.warmup,
        'revolutions_received': received,
        'rate_hz': round(received / duration, 3),
        'revolutions_skipped_end_to_end': gaps,
        'skipped_fraction': round(gaps / expected, 5) if expected else None,
        'sequence_restarts': restarts,
        'skipped_revolutions_per_stage': stage,
        'objects_per_revolution': round(objects / received, 2) if received else None,
        'latency_ms': {'p50': round(1e3 * percentile(lat, 0.5), 2),
                       'p99': round(1e3 * percentile(lat, 0.99), 2),
                       'max': round(1e3 * lat[-1], 2) if lat else None},
        'rss_mb': {'start': round(samples[0][1], 1), 'end': round(samples[-1][1], 1),
                   'max': round(max(r for _, r in samples), 1),
                   'slope_mb_per_hour': round(3600.0 * slope, 2)},
        'diagnostics_warning_seconds': warnings,
    }
    failures = []
    if summary['rss_mb']['end'] - summary['rss_mb']['start'] > args.max_rss_growth_mb:
        failures.append('RSS grew by more than %.0f MB' % args.max_rss_growth_mb)
    if expected and gaps / expected > args.max_skipped_fraction:
        failures.append('skipped more than %.1f%% of the revolutions'
                        % (100 * args.max_skipped_fraction))
    if summary['rate_hz'] < args.min_rate_hz:
        failures.append('objects at %.2f Hz < %.1f Hz' % (summary['rate_hz'], args.min_rate_hz))
    summary['failures'] = failures
    with open(args.out, 'w') as f:
        json.dump(summary, f, indent=2, sort_keys=True)
    print(json.dumps(summary, indent=2, sort_keys=True))
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())

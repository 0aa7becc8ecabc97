#!/usr/bin/env python3
"""Soak monitor, run by scripts/soak.sh against a running demo.launch.

Measures, for `--minutes` after `--warmup` seconds:
  * latency of every /objects message: receive wall time - header.stamp, p50 / p95 / p99 / max.
    The stamp is the revolution's last packet (velodyne_driver's convention, the default), so
    this is the figure of `scripts/run latency`: last packet -> /objects in another process
    (with ~timestamp_first_packet it would include the ~100 ms sweep). The detector's own
    figure (last packet -> its publish, on /diagnostics) is reported beside it;
  * revolutions skipped end to end: gaps in header.seq (numbered by the sensor and passed on
    by every stage), plus the per-stage totals of skipped_revolutions on /diagnostics;
  * resident memory (VmRSS) of the nodelet manager process, sampled every 10 s: at the end of
    the warm-up and at the end; also the least-squares slope over the measured period;
  * WARN/ERROR statuses seen on /diagnostics;
  * the output rate, counted three ways so that a wrong figure shows where it comes from:
    distinct revolutions received per second of the monotonic clock (the reported rate; the
    wall clock can be stepped during a long run), the same per second of header stamps (the
    source's own pace), and each stage's `outputs` total on /diagnostics per second. A message
    whose seq equals the previous one is counted as a duplicate, not as a revolution.
Writes a JSON summary (--out) and prints it; exits 1 when a bound is exceeded: RSS growth after
the warm-up, skipped fraction, output rate off the expected rate by more than a tolerance,
duplicates, or wall and monotonic clocks disagreeing (figures then unreliable).
"""
import argparse
import json
import re
import sys
import threading
import time
import xmlrpc.client


def manager_pid(name):
    import rosgraph
    master = rosgraph.Master('/soak_monitor')
    uri = master.lookupNode(name)
    code, _, pid = xmlrpc.client.ServerProxy(uri).getPid('/soak_monitor')
    if code != 1:
        raise RuntimeError('cannot get the pid of %s' % name)
    return pid


def publishers_of(topic):
    import rosgraph
    pubs, _, _ = rosgraph.Master('/soak_monitor').getSystemState()
    return sorted(sum((nodes for t, nodes in pubs if t == topic), []))


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


class SeqTracker:
    """Classifies the header.seq of successive messages of one topic: a new revolution (the
    next number, or after a gap of skipped ones), a duplicate (the same number again: one
    revolution delivered twice), or a restart (smaller: the source began numbering anew)."""

    def __init__(self, last_seq=None):
        self.last_seq = last_seq
        self.distinct = 0
        self.gaps = 0
        self.duplicates = 0
        self.restarts = 0

    def add(self, seq):
        last, self.last_seq = self.last_seq, seq
        if last is not None and seq == last:
            self.duplicates += 1
            return 'duplicate'
        self.distinct += 1
        if last is not None and seq > last + 1:
            self.gaps += seq - last - 1
            return 'gap'
        if last is not None and seq < last:
            self.restarts += 1
            return 'restart'
        return 'next'


def slope_per_hour(samples):
    """Least-squares slope of (t [s], value) samples, per hour."""
    n = len(samples)
    mt = sum(t for t, _ in samples) / n
    mv = sum(v for _, v in samples) / n
    var = sum((t - mt) ** 2 for t, _ in samples)
    return 3600.0 * sum((t - mt) * (v - mv) for t, v in samples) / var if var > 0 else 0.0


def check_bounds(summary, max_rss_growth_mb, max_skipped_fraction, expected_rate_hz,
                 rate_tolerance, max_clock_disagreement):
    """The reasons the soak fails (empty: passed)."""
    failures = []
    rss = summary['rss_mb']
    if rss['end'] - rss['start'] > max_rss_growth_mb:
        failures.append('RSS grew by %.1f MB after the warm-up (bound %.0f MB)'
                        % (rss['end'] - rss['start'], max_rss_growth_mb))
    fraction = summary['skipped_fraction']
    if fraction is None or fraction > max_skipped_fraction:
        failures.append('skipped %s of the revolutions (bound %.1f%%)'
                        % ('all' if fraction is None else '%.2f%%' % (100 * fraction),
                           100 * max_skipped_fraction))
    rate = summary['rate_hz']
    if expected_rate_hz > 0 and abs(rate - expected_rate_hz) > rate_tolerance * expected_rate_hz:
        failures.append('objects at %.2f Hz, expected %.1f Hz +- %.0f%%'
                        % (rate, expected_rate_hz, 100 * rate_tolerance))
    if summary['duplicate_messages'] > 0:
        failures.append('%d revolutions delivered more than once' % summary['duplicate_messages'])
    clocks = summary['clock_s']
    if abs(clocks['wall'] - clocks['monotonic']) > max_clock_disagreement * clocks['monotonic']:
        failures.append('wall clock advanced %.1f s in %.1f s of monotonic time: the clock was '
                        'stepped, latencies are unreliable' % (clocks['wall'], clocks['monotonic']))
    return failures


class Monitor:
    def __init__(self):
        self.lock = threading.Lock()
        self.measuring = False
        self.latencies = []
        self.received = 0
        self.objects = 0
        self.seq = SeqTracker()
        self.first_stamp = None
        self.last_stamp = None
        self.stage_skipped = {}
        self.stage_outputs = {}
        self.stage_latency = {}  # last /diagnostics latency window of each stage
        self.warnings = {}

    def on_objects(self, msg):
        import rospy
        now = rospy.Time.now()
        with self.lock:
            if not self.measuring:
                self.seq.last_seq = msg.header.seq
                return
            self.received += 1
            if self.seq.add(msg.header.seq) == 'duplicate':
                return
            self.objects += len(msg.objects)
            self.latencies.append((now - msg.header.stamp).to_sec())
            stamp = msg.header.stamp.to_sec()
            if self.first_stamp is None:
                self.first_stamp = stamp
            self.last_stamp = stamp

    def on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                values = {kv.key: kv.value for kv in status.values}
                if 'skipped_revolutions' in values:
                    self.stage_skipped[status.name] = int(values['skipped_revolutions'])
                if 'outputs' in values:
                    self.stage_outputs[status.name] = int(values['outputs'])
                if 'latency p50 [ms]' in values:
                    self.stage_latency[status.name] = {
                        q: float(values['latency %s [ms]' % q])
                        for q in ('p50', 'p95', 'p99', 'max')
                        if 'latency %s [ms]' % q in values}
                if self.measuring and status.level >= 1:
                    # One entry per kind of warning: the figures in the message vary.
                    key = '%s: %s' % (status.name, re.sub(r'[0-9.]+', '#', status.message))
                    self.warnings[key] = self.warnings.get(key, 0) + 1


def main():
    import rospy
    from diagnostic_msgs.msg import DiagnosticArray
    from urban_detection.msg import DetectedObjectArray

    parser = argparse.ArgumentParser()
    parser.add_argument('--minutes', type=float, default=30.0)
    parser.add_argument('--warmup', type=float, default=60.0, help='[s] before measuring')
    parser.add_argument('--manager', default='/urban_detection_manager')
    parser.add_argument('--out', required=True)
    parser.add_argument('--source', default='pcap', help='recorded in the summary')
    parser.add_argument('--max-rss-growth-mb', type=float, default=20.0,
                        help='[MB] bound on VmRSS(end) - VmRSS(end of warm-up)')
    parser.add_argument('--max-skipped-fraction', type=float, default=0.01)
    parser.add_argument('--expected-rate-hz', type=float, default=10.0,
                        help='[Hz] revolutions per second of the source (rpm / 60); 0: no check')
    parser.add_argument('--rate-tolerance', type=float, default=0.05,
                        help='accepted relative deviation of the output rate from the expected')
    parser.add_argument('--max-clock-disagreement', type=float, default=0.01,
                        help='accepted relative difference of wall and monotonic durations')
    args = parser.parse_args(rospy.myargv(sys.argv)[1:])

    rospy.init_node('soak_monitor', disable_signals=True)
    mon = Monitor()
    sub = rospy.Subscriber('/objects', DetectedObjectArray, mon.on_objects, queue_size=100,
                           tcp_nodelay=True)
    rospy.Subscriber('/diagnostics', DiagnosticArray, mon.on_diagnostics, queue_size=100)
    deadline = time.monotonic() + 60.0
    pid = None
    while pid is None and time.monotonic() < deadline:
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
        outputs_start = dict(mon.stage_outputs)
    # Durations on the monotonic clock; the wall clock only to detect that it was stepped.
    t0, wall0 = time.monotonic(), time.time()
    publishers_start = publishers_of('/objects')
    samples = [(0.0, rss_mb(pid))]
    end = t0 + 60.0 * args.minutes
    while time.monotonic() < end:
        time.sleep(min(10.0, max(0.0, end - time.monotonic())))
        samples.append((time.monotonic() - t0, rss_mb(pid)))
    with mon.lock:
        mon.measuring = False
        duration = time.monotonic() - t0
        wall_duration = time.time() - wall0
        lat = sorted(mon.latencies)
        received, seq = mon.received, mon.seq
        stage = {k: v - skipped_start.get(k, 0) for k, v in mon.stage_skipped.items()}
        stage_hz = {k: round((v - outputs_start[k]) / duration, 3)
                    for k, v in mon.stage_outputs.items() if k in outputs_start}
        stamp_span = (mon.last_stamp - mon.first_stamp) if mon.first_stamp is not None else 0.0
        warnings = dict(mon.warnings)
        stage_latency = dict(mon.stage_latency)
        objects = mon.objects
    expected = seq.distinct + seq.gaps
    summary = {
        'minutes': round(duration / 60.0, 2),
        'clock_s': {'monotonic': round(duration, 1), 'wall': round(wall_duration, 1)},
        'source': args.source,
        'warmup_s': args.warmup,
        'messages_received': received,
        'revolutions_received': seq.distinct,
        'duplicate_messages': seq.duplicates,
        'rate_hz': round(seq.distinct / duration, 3),
        'rate_by_stamps_hz': (round((seq.distinct - 1) / stamp_span, 3)
                              if stamp_span > 0 else None),
        'stage_output_hz': stage_hz,
        'objects_publishers': {'start': publishers_start, 'end': publishers_of('/objects')},
        'objects_connections': sub.get_num_connections(),
        'revolutions_skipped_end_to_end': seq.gaps,
        'skipped_fraction': round(seq.gaps / expected, 5) if expected else None,
        'sequence_restarts': seq.restarts,
        'skipped_revolutions_per_stage': stage,
        'objects_per_revolution': round(objects / seq.distinct, 2) if seq.distinct else None,
        'latency_ms': {'what': 'last packet of a revolution -> /objects received here',
                       'p50': round(1e3 * percentile(lat, 0.5), 2),
                       'p95': round(1e3 * percentile(lat, 0.95), 2),
                       'p99': round(1e3 * percentile(lat, 0.99), 2),
                       'max': round(1e3 * lat[-1], 2) if lat else None},
        'rss_mb': {'start': round(samples[0][1], 1), 'end': round(samples[-1][1], 1),
                   'max': round(max(r for _, r in samples), 1),
                   'slope_mb_per_hour': round(slope_per_hour(samples), 2)},
        'diagnostics_warning_seconds': warnings,
        'diagnostics_latency_ms': stage_latency,
    }
    summary['bounds'] = {'max_rss_growth_mb': args.max_rss_growth_mb,
                         'max_skipped_fraction': args.max_skipped_fraction,
                         'expected_rate_hz': args.expected_rate_hz,
                         'rate_tolerance': args.rate_tolerance}
    summary['failures'] = check_bounds(summary, args.max_rss_growth_mb,
                                       args.max_skipped_fraction, args.expected_rate_hz,
                                       args.rate_tolerance, args.max_clock_disagreement)
    with open(args.out, 'w') as f:
        json.dump(summary, f, indent=2, sort_keys=True)
    print(json.dumps(summary, indent=2, sort_keys=True), flush=True)
    l = summary['latency_ms']
    print('soak: %.2f Hz, latency last packet -> /objects p50 %s p95 %s p99 %s max %s ms, '
          '%d revolutions skipped, RSS %s -> %s MB' % (
              summary['rate_hz'], l['p50'], l['p95'], l['p99'], l['max'],
              summary['revolutions_skipped_end_to_end'], summary['rss_mb']['start'],
              summary['rss_mb']['end']), file=sys.stderr, flush=True)
    return 1 if summary['failures'] else 0


if __name__ == '__main__':
    sys.exit(main())

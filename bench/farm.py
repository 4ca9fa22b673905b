#!/usr/bin/python3
"""Farm throughput: a 12-frame shot rendered by one process and by `vdb_ewa submit` on a
one-node Slurm cluster started in a temporary folder (tests/slurm/slurm_cluster.py).

    /usr/bin/python3 bench/farm.py --cli build/cmd/vdb_ewa/vdb_ewa [--rounds 3] [--out DIR]

Configurations, run in interleaved rounds (each round runs every configuration once, on a
fresh output folder):
  direct    vdb_ewa render --job shot.json (one process, threads = all cores)
  c4 x1cpu  vdb_ewa submit --chunk 4 --cpus 1: 3 tasks, 2 at a time
  c4 x2cpu  vdb_ewa submit --chunk 4 --cpus 2: 3 tasks one at a time, each on both cores
  c1 x1cpu  vdb_ewa submit --chunk 1 --cpus 1: 12 tasks, 2 at a time
A farm run is timed from the submit command to the last output (outputs polled every 0.1 s),
and also to the job leaving the queue.

Per-task overhead: each task's log gives its frames' render times ("frame N done: ... (0.52 s,
...)"), measured as they ran (so with the other task's contention). A list schedule of the
tasks in array order on the node's slots (2 / cpus) with those durations is the time the farm
would take with no overhead; the overhead per task is the o that, added to every task, makes
that schedule last as long as the measured time (bisection). It covers everything in a task
but rendering frames: Slurm's scheduling of the task, slurmstepd's launch and the process's
start-up (options, colour config), and the gap before the next task's start. The simpler
(farm - direct x f) / tasks, with f the ratio of ideal farm time to direct time, needs f,
which differs per configuration (1-thread frames are not 2x the 2-thread ones), so the
schedule is fitted on the frame times measured in each run instead.
"""

import argparse
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.dont_write_bytecode = True   # no __pycache__ in the source tree
sys.path.insert(0, os.path.join(HERE, "..", "tests", "slurm"))
from slurm_cluster import SlurmCluster, ClusterUnavailable  # noqa: E402

FRAMES = list(range(1, 13))
NODE_CPUS = 2
_DONE_RE = re.compile(r"^vdb_ewa: frame (-?\d+) done: .* \((\d+(?:\.\d+)?) s", re.M)

CONFIGS = [
    # name, chunk, cpus (None: the direct render)
    ("direct", None, None),
    ("c4 x1cpu", 4, 1),
    ("c4 x2cpu", 4, 2),
    ("c1 x1cpu", 1, 1),
]


def run(cmd, env=None, timeout=900):
    r = subprocess.run([str(c) for c in cmd], env=env, stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, universal_newlines=True, timeout=timeout)
    if r.returncode != 0:
        raise RuntimeError("%s: exit %d\n%s\n%s" % (" ".join(map(str, cmd)), r.returncode,
                                                    r.stdout[-2000:], r.stderr[-2000:]))
    return r


def frame_times(text):
    return {int(f): float(s) for f, s in _DONE_RE.findall(text)}


def failed_tasks(logs, job_id):
    """The last lines (progress lines left out) of the logs of tasks that wrote no 'done'."""
    found = []
    for name in sorted(os.listdir(logs)):
        if not name.startswith(job_id + "_"):
            continue
        with open(os.path.join(logs, name), errors="replace") as f:
            text = f.read()
        if "vdb_ewa: frame" in text and "failed" not in text and "interrupted" not in text:
            continue
        kept = [ln for ln in text.splitlines() if ln.strip() and not re.match(r"^\d+% done", ln)]
        found.append("%s: %s" % (name, " | ".join(kept[-4:]) or "(empty)"))
    return "\n".join(found) or "(every task's log has done frames)"


def list_schedule(durations, slots):
    """Makespan of tasks started in order, each on the first free slot."""
    free = [0.0] * slots
    for d in durations:
        i = free.index(min(free))
        free[i] += d
    return max(free) if durations else 0.0


def fit_overhead(durations, slots, measured):
    """o >= 0 with list_schedule([d + o for d in durations]) == measured (None if the ideal
    schedule is already longer than the measurement)."""
    if list_schedule(durations, slots) > measured:
        return None
    lo, hi = 0.0, measured
    for _ in range(60):
        mid = (lo + hi) / 2
        if list_schedule([d + mid for d in durations], slots) < measured:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


class CpuMonitor:
    """The share of the machine's CPU time that other processes took during a run (another
    build or test on the same machine skews the figures): the whole machine's busy time
    (/proc/stat) less that of the processes whose command line mentions the bench's folder
    (vdb_ewa, the daemons), sampled every 0.2 s (a process's last 0.2 s before it exits is
    missed, and so counted as other; slurmstepd is counted as other too: small either way)."""

    def __init__(self, mark):
        self.mark = mark.encode()
        self.ticks = os.sysconf("SC_CLK_TCK")

    @staticmethod
    def busy():
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:]]
        return sum(v) - v[3] - v[4]   # all but idle and iowait

    def ours(self):
        for entry in os.listdir("/proc"):
            if not entry.isdigit():
                continue
            try:
                with open("/proc/%s/cmdline" % entry, "rb") as f:
                    if self.mark not in f.read():
                        continue
                with open("/proc/%s/stat" % entry, "rb") as f:
                    stat = f.read()
            except OSError:
                continue
            fields = stat[stat.rfind(b")") + 2:].split()
            self.seen[int(entry)] = int(fields[11]) + int(fields[12])   # utime + stime

    def __enter__(self):
        self.seen = {}
        self.ours()
        self.start_seen = dict(self.seen)
        self.t0, self.b0 = time.monotonic(), self.busy()
        self.done = threading.Event()
        self.thread = threading.Thread(target=self.loop, daemon=True)
        self.thread.start()
        return self

    def loop(self):
        while not self.done.wait(0.2):
            self.ours()

    def __exit__(self, *exc):
        self.done.set()
        self.thread.join()
        self.ours()
        wall = time.monotonic() - self.t0
        busy = self.busy() - self.b0
        ours = sum(v - self.start_seen.get(pid, 0) for pid, v in self.seen.items())
        self.other = max(0.0, (busy - ours) / self.ticks / (wall * (os.cpu_count() or 1)))
        return False


class Bench:
    def __init__(self, cli, out, res, keep):
        self.cli = cli
        self.out = out
        self.res = res
        self.keep = keep
        self.results = {name: [] for name, _, _ in CONFIGS}

    def path(self, *p):
        return os.path.join(self.out, *p)

    def setup(self):
        for name in ("grids", "runs"):
            shutil.rmtree(self.path(name), ignore_errors=True)
        os.makedirs(self.path("grids"))
        os.makedirs(self.path("runs"))
        for f in FRAMES:
            run([self.cli, "make-grid", "cloud", self.path("grids", "in.%04d.vdb" % f),
                 "--voxel-size", "%.3f" % (0.020 + 0.001 * f)])

    def job(self, tag):
        folder = self.path("runs", tag)
        os.makedirs(folder)
        job = {"input": self.path("grids", "in.####.vdb"),
               "output": os.path.join(folder, "out.####.exr"),
               "frames": "1-12", "res": self.res, "lookat": [0, 0, 0], "translate": [0, 0.5, 3]}
        p = self.path("runs", tag + ".json")
        with open(p, "w") as f:
            json.dump(job, f, indent=2)
        return p, folder

    def count_outputs(self, folder):
        return sum(1 for n in os.listdir(folder) if re.fullmatch(r"out\.\d{4}\.exr", n))

    def direct(self, tag):
        job, folder = self.job(tag)
        t = time.monotonic()
        r = run([self.cli, "render", "--job", job])
        wall = time.monotonic() - t
        times = frame_times(r.stdout)
        assert sorted(times) == FRAMES, r.stdout
        self.cleanup(tag, folder)
        return {"wall": wall, "empty": wall, "render": sum(times.values()), "overhead": None,
                "start": None}

    def farm(self, cluster, tag, chunk, cpus):
        job, folder = self.job(tag)
        logs = self.path("runs", tag + ".farm", "logs")
        t0 = time.monotonic()
        r = run([self.cli, "submit", job, "--frames", "1-12", "--chunk", chunk, "--cpus", cpus,
                 "--mem", "1G", "--parsable"], env=cluster.env)
        job_id = r.stdout.strip()
        t_start = t_last = t_empty = None
        while True:
            now = time.monotonic()
            if now - t0 > 900:
                raise RuntimeError("%s: job %s not done after 900 s" % (tag, job_id))
            if t_start is None and os.path.isdir(logs) and os.listdir(logs):
                t_start = now
            if t_last is None and self.count_outputs(folder) == len(FRAMES):
                t_last = now
            if not cluster.queue(job_id):
                t_empty = now
                if t_last is None:
                    if self.count_outputs(folder) != len(FRAMES):
                        raise RuntimeError("%s: job %s left the queue with %d outputs; logs in %s:"
                                           "\n%s" % (tag, job_id, self.count_outputs(folder),
                                                     logs, failed_tasks(logs, job_id)))
                    t_last = now
                break
            time.sleep(0.1)
        tasks = math.ceil(len(FRAMES) / chunk)
        durations = []
        for task in range(tasks):
            with open(os.path.join(logs, "%s_%d.log" % (job_id, task))) as f:
                times = frame_times(f.read())
            expected = FRAMES[task * chunk:(task + 1) * chunk]
            if sorted(times) != expected:
                raise RuntimeError("%s: task %d's log has frames %s, expected %s"
                                   % (tag, task, sorted(times), expected))
            durations.append(sum(times.values()))
        slots = NODE_CPUS // cpus
        wall = t_last - t0
        self.cleanup(tag, folder)
        return {"wall": wall, "empty": t_empty - t0, "render": sum(durations),
                "ideal": list_schedule(durations, slots),
                "overhead": fit_overhead(durations, slots, wall),
                "start": (t_start - t0) if t_start is not None else None, "tasks": tasks,
                "slots": slots}

    def cleanup(self, tag, folder):
        if not self.keep:
            shutil.rmtree(folder, ignore_errors=True)

    def round(self, cluster, i):
        for name, chunk, cpus in CONFIGS:
            tag = "r%d_%s" % (i, name.replace(" ", "_"))
            with CpuMonitor(self.out) as cpu:
                res = self.direct(tag) if chunk is None else self.farm(cluster, tag, chunk, cpus)
            res["other"] = cpu.other
            self.results[name].append(res)
            extra = ""
            if chunk is not None:
                extra = ", queue empty %.2f s, ideal %.2f s, overhead/task %s" % (
                    res["empty"], res["ideal"],
                    "%.2f s" % res["overhead"] if res["overhead"] is not None else "-")
            print("  round %d %-9s %6.2f s (frames' render times sum %.2f s%s; other "
                  "processes took %.0f %% of the CPUs)" % (i + 1, name, res["wall"],
                                                          res["render"], extra,
                                                          100 * res["other"]), flush=True)

    def table(self):
        def med(name, key):
            vals = [r[key] for r in self.results[name] if r.get(key) is not None]
            return statistics.median(vals) if vals else None

        def fmt(v, f="%.2f"):
            return f % v if v is not None else "-"

        direct = med("direct", "wall")
        lines = [
            "| configuration | tasks x slots | submit to last output (s) | vs direct | "
            "to queue empty (s) | sum of frame times (s) | ideal schedule (s) | "
            "overhead a task (s) | submit to first task (s) | other processes' CPU share |",
            "|---|---|---|---|---|---|---|---|---|---|",
        ]
        for name, chunk, cpus in CONFIGS:
            wall = med(name, "wall")
            shape = "1 process, %d threads" % NODE_CPUS if chunk is None else "%d x %d (%d cpu%s)" % (
                math.ceil(len(FRAMES) / chunk), NODE_CPUS // cpus, cpus, "" if cpus == 1 else "s")
            lines.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                name if chunk is None else "submit --chunk %d --cpus %d" % (chunk, cpus), shape,
                fmt(wall), fmt(wall / direct, "%.2fx") if wall and direct else "-",
                fmt(med(name, "empty")), fmt(med(name, "render")), fmt(med(name, "ideal")),
                fmt(med(name, "overhead")), fmt(med(name, "start")),
                "%.0f %%" % (100 * max(r["other"] for r in self.results[name]))))
        return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cli", required=True, help="the vdb_ewa executable")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--res", default="1280x720", help="image size (default 1280x720: 1-2 s a "
                    "frame on one thread)")
    ap.add_argument("--out", default="/tmp/vdb_ewa_farm_bench", help="working folder")
    ap.add_argument("--keep", action="store_true", help="keep the rendered frames")
    ap.add_argument("--batch-sched-delay", type=int, default=None, metavar="S",
                    help="slurm.conf SchedulerParameters=batch_sched_delay=S (default: Slurm's, "
                    "3 s: array tasks start on a 3 s cadence; 0 leaves slurmctld's 1 s loop)")
    a = ap.parse_args()
    cli = os.path.abspath(a.cli)
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    bench = Bench(cli, out, a.res, a.keep)
    t0 = time.monotonic()
    bench.setup()
    print("12 grids (voxel 0.021-0.032) made in %.1f s; %s, %d rounds; load average %.2f"
          % (time.monotonic() - t0, a.res, a.rounds, os.getloadavg()[0]), flush=True)
    try:
        sched = (None if a.batch_sched_delay is None
                 else "batch_sched_delay=%d" % a.batch_sched_delay)
        with SlurmCluster(out, cpus=NODE_CPUS, memory_mb=8000,
                          scheduler_parameters=sched) as cluster:
            for i in range(a.rounds):
                bench.round(cluster, i)
    except ClusterUnavailable as e:
        print("SKIP: " + e.reason)
        return 77
    print()
    print("Medians of %d rounds, %s, 12 frames, node of %d CPUs (nproc %d), batch_sched_delay "
          "%s; load average at the end %.2f:" % (
              a.rounds, a.res, NODE_CPUS, os.cpu_count(),
              "%d s" % a.batch_sched_delay if a.batch_sched_delay is not None else "3 s (default)",
              os.getloadavg()[0]))
    print()
    print(bench.table())
    print()
    print("other processes' CPU share: the largest over the rounds; figures are only "
          "meaningful near 0 %.")
    print("overhead a task: o such that a list schedule of the tasks (their logged frame times "
          "+ o each) on the slots lasts the measured submit-to-last-output time; see the "
          "docstring.")
    print("total %.0f s" % (time.monotonic() - t0))
    return 0


if __name__ == "__main__":
    sys.exit(main())

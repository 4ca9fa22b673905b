#!/usr/bin/python3
"""vdb_ewa's Slurm support on a real one-node cluster (tests/slurm/slurm_cluster.py).

    /usr/bin/python3 tests/slurm/test_slurm.py --cli build/cmd/vdb_ewa/vdb_ewa --out /tmp/slurm_test

Exit 0: pass, 1: fail, 77: skipped (no Slurm or munge here, not root, the daemons would not
start, or no OpenImageIO module); ctest reads 77 as skipped (SKIP_RETURN_CODE 77).

1. A 12-frame shot (12 different grids), rendered directly by `vdb_ewa render --job`.
2. `vdb_ewa submit --chunk 4 --cpus 1`: 3 array tasks; every output equals the direct render
   (pixels and channel names), each task's log lists exactly its chunk's frames, and
   `vdb_ewa status` reports 12 done.
3. A second shot cancelled with scancel once a few frames are out: no partial frame and no
   temporary file, `vdb_ewa status` exits 1 listing the missing frames; resubmitted with
   `--skip-existing`, only the missing frames are rendered (each once), the earlier outputs
   are untouched (same inode and mtime), and all 12 equal the direct render.
"""

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

sys.dont_write_bytecode = True   # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from slurm_cluster import SlurmCluster, ClusterUnavailable, ClusterLeftovers  # noqa: E402

FRAMES = list(range(1, 13))
CHUNK = 4
RES = "640x360"           # about 0.3-0.6 s a frame on one thread
JOB_TIMEOUT = 150.0       # seconds for a submitted job to leave the queue
SKIP = 77

_OUTPUT_RE = re.compile(r"^out\.(\d{4})\.exr$")
_DONE_RE = re.compile(r"^vdb_ewa: frame (-?\d+) done: ", re.M)
_SKIPPED_RE = re.compile(r"^vdb_ewa: frame (-?\d+) skipped: ", re.M)
_FAILED_RE = re.compile(r"^vdb_ewa: frame (-?\d+) failed", re.M)
_INTERRUPTED_RE = re.compile(r"^vdb_ewa: frame (-?\d+) interrupted", re.M)


class Failure(Exception):
    """A check that makes the rest of the test meaningless."""


class Test:
    def __init__(self, cli, out):
        self.cli = cli
        self.out = out
        self.failures = []
        self.timings = []   # (what, seconds)
        self.env = None     # the cluster's environment, once up

    # ---- reporting -------------------------------------------------------------------------
    def check(self, ok, message):
        if not ok:
            self.failures.append(message)
            print("FAIL: " + message, flush=True)
        return ok

    def note(self, message):
        print("  " + message, flush=True)

    def timed(self, what, seconds):
        self.timings.append((what, seconds))
        self.note("%s: %.2f s" % (what, seconds))

    # ---- running vdb_ewa -------------------------------------------------------------------
    def vdb(self, args, expect=(0,), timeout=300):
        """Run vdb_ewa ARGS (with the cluster's environment when there is one)."""
        cmd = [self.cli] + [str(a) for a in args]
        r = subprocess.run(cmd, env=self.env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           universal_newlines=True, timeout=timeout)
        if expect is not None and r.returncode not in expect:
            raise Failure("%s: exit %d, expected %s\nstdout: %s\nstderr: %s" % (
                " ".join(cmd), r.returncode, "/".join(map(str, expect)), r.stdout.strip()[-2000:],
                r.stderr.strip()[-2000:]))
        return r

    # ---- the shot --------------------------------------------------------------------------
    def path(self, *parts):
        return os.path.join(self.out, *parts)

    def clean(self):
        """Remove what an earlier run of this test left in --out (only the names it makes)."""
        os.makedirs(self.out, exist_ok=True)
        for name in os.listdir(self.out):
            if (name in ("grids", "direct") or re.match(r"^farm\d*$", name)
                    or re.match(r"^shot\d*(\.json|\.farm)$", name) or name.startswith("cluster.")):
                p = self.path(name)
                if os.path.isdir(p) and not os.path.islink(p):
                    shutil.rmtree(p)
                else:
                    os.remove(p)

    def make_shot(self):
        os.makedirs(self.path("grids"))
        t = time.monotonic()
        for f in FRAMES:
            self.vdb(["make-grid", "cloud", self.path("grids", "in.%04d.vdb" % f),
                      "--voxel-size", "%.3f" % (0.030 + 0.001 * f)])
        self.timed("12 grids made", time.monotonic() - t)

    def write_job(self, name, out_folder):
        job = {
            "input": self.path("grids", "in.####.vdb"),
            "output": self.path(out_folder, "out.####.exr"),
            "frames": "1-12",
            "res": RES,
            "lookat": [0, 0, 0],
            "translate": [0, 0.5, 3],
        }
        os.makedirs(self.path(out_folder), exist_ok=True)   # vdb_ewa wants it to exist
        p = self.path(name)
        with open(p, "w") as f:
            json.dump(job, f, indent=2)
        return p

    def direct_render(self):
        os.makedirs(self.path("direct"))
        t = time.monotonic()
        self.vdb(["render", "--job", self.path("shot.json"), self.path("grids", "in.####.vdb"),
                  self.path("direct", "out.####.exr"), "--frames", "1-12"])
        self.timed("direct render of 12 frames (all cores)", time.monotonic() - t)
        for f in FRAMES:
            if not os.path.isfile(self.path("direct", "out.%04d.exr" % f)):
                raise Failure("the direct render wrote no frame %d" % f)
        self.direct = {f: read_pixels(self.path("direct", "out.%04d.exr" % f)) for f in FRAMES}

    # ---- farm helpers ----------------------------------------------------------------------
    def outputs(self, folder):
        """{frame: path} of the finished outputs in folder (hidden temporary files excluded)."""
        found = {}
        try:
            names = os.listdir(self.path(folder))
        except FileNotFoundError:
            return found
        for name in names:
            m = _OUTPUT_RE.match(name)
            if m:
                found[int(m.group(1))] = self.path(folder, name)
        return found

    def hidden_files(self, folder):
        try:
            return sorted(n for n in os.listdir(self.path(folder)) if n.startswith("."))
        except FileNotFoundError:
            return []

    def submit(self, job, extra=(), parsable=True):
        args = ["submit", job, "--frames", "1-12", "--chunk", CHUNK, "--cpus", 1, "--mem", "500M"]
        args += list(extra)
        if parsable:
            args.append("--parsable")
        r = self.vdb(args)
        if parsable:
            job_id = r.stdout.strip()
            if not re.fullmatch(r"\d+", job_id):
                raise Failure("submit --parsable printed %r, not a job id" % r.stdout)
        else:
            m = re.search(r"vdb_ewa: submitted job (\d+)", r.stdout)
            if not m:
                raise Failure("submit printed no 'vdb_ewa: submitted job ID': %r" % r.stdout)
            job_id = m.group(1)
        return job_id, r

    def wait_job(self, cluster, job_id, what):
        t = time.monotonic()
        if not cluster.wait_queue_empty(job_id, timeout=JOB_TIMEOUT):
            raise Failure("%s: job %s still in the queue after %.0f s: %s" % (
                what, job_id, JOB_TIMEOUT, cluster.queue(job_id)))
        return time.monotonic() - t

    def log(self, farm, job_id, task):
        p = os.path.join(farm, "logs", "%s_%d.log" % (job_id, task))
        try:
            with open(p, errors="replace") as f:
                return p, f.read()
        except FileNotFoundError:
            return p, None

    def compare_outputs(self, folder, frames, what):
        outs = self.outputs(folder)
        for f in frames:
            if not self.check(f in outs, "%s: frame %d has no output in %s" % (what, f, folder)):
                continue
            try:
                got = read_pixels(outs[f])
            except Exception as e:   # noqa: BLE001 - any read error is the failure reported
                self.check(False, "%s: %s does not read: %s" % (what, outs[f], e))
                continue
            diff = compare(got, self.direct[f])
            self.check(diff is None, "%s: frame %d differs from the direct render: %s"
                       % (what, f, diff))

    def status(self, job):
        r = self.vdb(["status", job], expect=None)
        return r.returncode, r.stdout, r.stderr

    # ---- part c: a whole shot on the farm -----------------------------------------------
    def farm_whole_shot(self, cluster):
        print("== submit shot.json: 12 frames, chunks of 4, 1 CPU a task", flush=True)
        job = self.path("shot.json")
        t = time.monotonic()
        job_id, _ = self.submit(job)
        self.note("job %s submitted (%.2f s)" % (job_id, time.monotonic() - t))
        # while it runs: not done, and every frame is running, queued or done (status asks
        # squeue, through the cluster's SLURM_CONF)
        code, out, err = self.status(job)
        first = out.splitlines()[0] if out else ""
        m = re.search(r"(\d+) done, (\d+) running, (\d+) queued, (\d+) failed, (\d+) missing",
                      first)
        self.note("status while it runs: " + first)
        if self.check(m is not None, "status shot.json: first line %r (stderr %r)" % (first, err)):
            done, running, queued, failed, missing = map(int, m.groups())
            self.check(code == 1 and done < 12 and running + queued > 0 and failed == 0
                       and missing == 0 and done + running + queued == 12,
                       "status shot.json while the job runs: exit %d, %r" % (code, first))
        self.wait_job(cluster, job_id, "shot.json")
        self.timed("farm: submit to queue empty, 3 tasks on 2 CPUs", time.monotonic() - t)
        self.compare_outputs("farm", FRAMES, "farm")
        self.check(not self.hidden_files("farm"),
                   "farm: hidden (temporary) files left: %s" % self.hidden_files("farm"))
        farm = self.path("shot.farm")
        for name in ("%s.sbatch" % job_id, "%s.json" % job_id):
            self.check(os.path.isfile(os.path.join(farm, name)),
                       "submit wrote no %s in %s" % (name, farm))
        for task in range(3):
            expected = FRAMES[task * CHUNK:(task + 1) * CHUNK]
            p, text = self.log(farm, job_id, task)
            if not self.check(text is not None, "no log %s" % p):
                continue
            done = [int(x) for x in _DONE_RE.findall(text)]
            self.check(done == expected, "%s: 'frame N done' lines for %s, expected %s; it ends:"
                       "\n%s" % (p, done, expected, log_excerpt(text)))
            failed = _FAILED_RE.findall(text)
            self.check(not failed, "%s: frames failed: %s" % (p, failed))
            # the task took the CPUs and memory Slurm granted (--cpus 1, --mem 500M): one thread
            # and a frame budget of 3/4 of 500 MB
            grant = ("vdb_ewa: task %d: frames %d-%d; 1 thread (SLURM_CPUS_PER_TASK=1), a frame's "
                     "memory budget 375 MB (3/4 of SLURM_MEM_PER_NODE=500 MB)\n"
                     % (task, expected[0], expected[-1]))
            self.check(grant in text, "%s: no line %r; it begins:\n%s" % (p, grant, text[:600]))
        code, out, err = self.status(job)
        first = out.splitlines()[0] if out else ""
        self.check(code == 0, "status shot.json: exit %d, expected 0 (%s %s)" % (code, out, err))
        self.check(re.search(r"\b12 done\b", first) is not None,
                   "status shot.json: first line %r does not report 12 done" % first)
        self.note("status: " + first)

    # ---- part d: cancel and resume -------------------------------------------------------
    def farm_cancel_and_resume(self, cluster):
        attempts = [("shot2.json", "farm2", []), ("shot3.json", "farm3", ["--max-running", "1"])]
        for i, (name, folder, extra) in enumerate(attempts):
            print("== submit %s%s, cancel it after 2 frames" % (name, " " + " ".join(extra)
                                                                  if extra else ""), flush=True)
            result = self.cancel_after_two(cluster, name, folder, extra)
            if result is not None:
                break
            if i + 1 == len(attempts):
                raise Failure("the cancel landed after every frame was written, twice (even "
                              "with --max-running 1): the machine is too fast or the poll too "
                              "slow for this test's frames")
            self.note("the cancel landed after every frame was written: again, one task at a time")
        job, folder, job_id, before = result
        self.resume(cluster, job, folder, job_id, before)

    def cancel_after_two(self, cluster, name, folder, extra):
        job = self.write_job(name, folder)
        farm = self.path(name.replace(".json", ".farm"))
        t = time.monotonic()
        job_id, r = self.submit(job, extra, parsable=False)
        self.note(r.stdout.strip())
        while True:
            outs = self.outputs(folder)
            if len(outs) >= 2:
                break
            if not cluster.queue(job_id):
                raise Failure("%s: job %s left the queue with %d outputs before the cancel"
                              % (name, job_id, len(outs)))
            if time.monotonic() - t > JOB_TIMEOUT:
                raise Failure("%s: fewer than 2 outputs %.0f s after submit" % (name, JOB_TIMEOUT))
            time.sleep(0.02)
        tc = time.monotonic()
        cluster.run(["scancel", job_id], check=True)
        self.note("scancel %s with %d outputs, %.2f s after submit" % (job_id, len(outs), tc - t))
        self.wait_job(cluster, job_id, name + " (cancelled)")
        stop = time.monotonic() - tc
        self.timed("scancel to queue empty", stop)
        outs = self.outputs(folder)
        if len(outs) == len(FRAMES):
            return None
        self.note("%d outputs after the cancel: frames %s" % (len(outs), sorted(outs)))
        # A task stopped by SIGKILL (KillWait later) can leave its temporary file; vdb_ewa's
        # SIGTERM handling must stop it well before.
        self.check(stop < cluster.kill_wait,
                   "the cancelled tasks took %.1f s to leave the queue: not stopped by SIGTERM "
                   "before KillWait's SIGKILL (%d s)?" % (stop, cluster.kill_wait))
        hidden = self.hidden_files(folder)
        self.check(not hidden, "%s: files left after the cancel: %s" % (folder, hidden))
        self.compare_outputs(folder, sorted(outs), "after the cancel")
        # each task that was running when cancelled reports its frame in flight as interrupted
        frames = FRAMES
        for task in range(math.ceil(len(frames) / CHUNK)):
            chunk = frames[task * CHUNK:(task + 1) * CHUNK]
            p, text = self.log(farm, job_id, task)
            if text is None:
                self.note("task %d never started (no log)" % task)
                continue
            done = [int(x) for x in _DONE_RE.findall(text)]
            interrupted = [int(x) for x in _INTERRUPTED_RE.findall(text)]
            self.note("task %d: done %s, interrupted %s" % (task, done, interrupted))
            self.check(set(done) == {f for f in chunk if f in outs},
                       "%s: done lines %s, but the outputs of its chunk %s are %s"
                       % (p, done, chunk, [f for f in chunk if f in outs]))
            if len(done) < len(chunk):
                self.check(len(interrupted) == 1 and interrupted[0] in chunk
                           and interrupted[0] not in done,
                           "%s: a task cancelled in its chunk %s (done %s) should report one "
                           "'frame N interrupted', got %s" % (p, chunk, done, interrupted))
        missing = [f for f in FRAMES if f not in outs]
        code, out, err = self.status(job)
        self.note("status after the cancel (exit %d):\n    %s" % (code, out.strip().replace(
            "\n", "\n    ")))
        self.check(code == 1, "status %s after the cancel: exit %d, expected 1" % (name, code))
        listed = set()
        for line in out.splitlines()[1:]:
            if line.startswith("missing: "):
                listed |= parse_frame_list(line[len("missing: "):].split(" ")[0])
        self.check(listed == set(missing), "status %s: its 'missing:' lines list %s, the missing "
                   "frames are %s" % (name, sorted(listed), missing))
        first = out.splitlines()[0] if out else ""
        self.check(re.search(r"\b%d done\b.*\b%d missing\b" % (len(outs), len(missing)), first)
                   is not None, "status %s: first line %r, expected %d done and %d missing"
                   % (name, first, len(outs), len(missing)))
        before = {f: stat_id(p) for f, p in outs.items()}
        return job, folder, job_id, before

    def resume(self, cluster, job, folder, first_id, before):
        name = os.path.basename(job)
        farm = job[:-len(".json")] + ".farm"
        missing = [f for f in FRAMES if f not in before]
        print("== resubmit %s --skip-existing: frames %s" % (name, compact(missing)), flush=True)
        t = time.monotonic()
        job_id, _ = self.submit(job, ["--skip-existing"])
        self.check(job_id != first_id, "the resubmission got the same job id %s" % job_id)
        self.wait_job(cluster, job_id, name + " (resubmitted)")
        self.timed("resubmission: submit to queue empty", time.monotonic() - t)
        self.compare_outputs(folder, FRAMES, "after the resubmission")
        self.check(not self.hidden_files(folder), "%s: hidden files left: %s"
                   % (folder, self.hidden_files(folder)))
        for f, ident in before.items():
            now = stat_id(self.path(folder, "out.%04d.exr" % f))
            self.check(now == ident, "frame %d was rewritten by the resubmission (inode, mtime "
                       "%s -> %s)" % (f, ident, now))
        rendered = []
        tasks = math.ceil(len(missing) / CHUNK)
        for task in range(tasks):
            chunk = missing[task * CHUNK:(task + 1) * CHUNK]
            p, text = self.log(farm, job_id, task)
            if not self.check(text is not None, "no log %s" % p):
                continue
            done = [int(x) for x in _DONE_RE.findall(text)]
            rendered += done
            self.check(done == chunk, "%s: frames done %s, expected its chunk %s of the missing "
                       "frames; it ends:\n%s" % (p, done, chunk, log_excerpt(text)))
            self.check(not _SKIPPED_RE.findall(text) and not _FAILED_RE.findall(text),
                       "%s: skipped or failed frames:\n%s" % (p, text))
        p, text = self.log(farm, job_id, tasks)
        self.check(text is None, "the resubmission has a task %d beyond the %d missing frames' "
                   "%d chunks: %s" % (tasks, len(missing), tasks, p))
        self.check(sorted(rendered) == missing,
                   "the resubmission rendered %s, the missing frames were %s" % (rendered, missing))
        code, out, err = self.status(job)
        first = out.splitlines()[0] if out else ""
        self.check(code == 0 and re.search(r"\b12 done\b", first) is not None,
                   "status %s after the resubmission: exit %d, %r" % (name, code, first))
        self.note("status: " + first)


def log_excerpt(text, lines=6):
    """A task log's last lines but the progress ones ('35% done (...)')."""
    kept = [ln for ln in text.splitlines() if ln.strip() and not re.match(r"^\d+% done", ln)]
    return "\n".join(kept[-lines:]) or "(nothing but progress)"


# ---- images --------------------------------------------------------------------------------
def read_pixels(path):
    import OpenImageIO as oiio
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise IOError("cannot open %s: %s" % (path, oiio.geterror()))
    try:
        spec = inp.spec()
        pixels = inp.read_image(format="float")
        if pixels is None:
            raise IOError("cannot read %s: %s" % (path, inp.geterror()))
        return {"channels": tuple(spec.channelnames), "size": (spec.width, spec.height),
                "pixels": pixels}
    finally:
        inp.close()


def compare(a, b):
    """None when a and b hold the same channels and bit-identical pixels, else why not."""
    import numpy as np
    if a["channels"] != b["channels"]:
        return "channels %s vs %s" % (a["channels"], b["channels"])
    if a["size"] != b["size"]:
        return "size %s vs %s" % (a["size"], b["size"])
    pa = np.ascontiguousarray(a["pixels"], dtype=np.float32)
    pb = np.ascontiguousarray(b["pixels"], dtype=np.float32)
    if pa.shape != pb.shape:
        return "pixel arrays %s vs %s" % (pa.shape, pb.shape)
    same = pa.view(np.uint32) == pb.view(np.uint32)
    if same.all():
        return None
    with np.errstate(invalid="ignore", over="ignore"):
        diff = np.abs(pa.astype(np.float64) - pb.astype(np.float64))
    diff = diff[~same & np.isfinite(diff)]
    return "%d of %d values differ (largest finite difference %g)" % (
        (~same).sum(), same.size, diff.max() if diff.size else float("nan"))


def stat_id(path):
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return None
    return (st.st_ino, st.st_mtime_ns)


def parse_frame_list(text):
    """'1-4,7,9-12x2' -> a set of frames (vdb_ewa's --frames syntax)."""
    frames = set()
    for item in filter(None, text.split(",")):
        m = re.fullmatch(r"(-?\d+)(?:-(-?\d+)(?:x(\d+))?)?", item)
        if not m:
            raise ValueError("not a frame list item: %r" % item)
        a = int(m.group(1))
        b = int(m.group(2)) if m.group(2) else a
        frames.update(range(a, b + 1, int(m.group(3) or 1)))
    return frames


def compact(frames):
    return ",".join(str(f) for f in frames)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cli", required=True, help="the vdb_ewa executable")
    ap.add_argument("--out", required=True, help="working folder (its test files are replaced)")
    a = ap.parse_args()
    cli = os.path.abspath(a.cli)
    out = os.path.abspath(a.out)
    if not (os.path.isfile(cli) and os.access(cli, os.X_OK)):
        print("FAIL: no vdb_ewa executable at %s" % cli)
        return 1
    try:
        import OpenImageIO  # noqa: F401
        import numpy  # noqa: F401
    except ImportError as e:
        print("SKIP: %s (the outputs are compared with OpenImageIO's python module)" % e)
        return SKIP

    t0 = time.monotonic()
    test = Test(cli, out)
    try:
        SlurmCluster.check_prerequisites()   # skip before making the shot
        test.clean()
        print("== the shot: 12 grids and a direct render", flush=True)
        test.make_shot()
        test.write_job("shot.json", "farm")
        test.direct_render()
        t = time.monotonic()
        cluster = SlurmCluster(out, cpus=2, memory_mb=8000)
        try:
            with cluster:
                test.timed("cluster start", time.monotonic() - t)
                if cluster.stale:
                    test.note("killed leftovers of an earlier run: %s" % cluster.stale)
                test.env = cluster.env
                try:
                    test.farm_whole_shot(cluster)
                    test.farm_cancel_and_resume(cluster)
                finally:
                    test.env = None
                    t = time.monotonic()
            test.timed("cluster stop", time.monotonic() - t)
        except ClusterLeftovers:
            pass   # reported below
        finally:
            # whatever ended the test, what the cluster left running is a failure too
            if cluster.leftovers:
                test.check(False, "cluster processes left running after stop (killed): %s"
                           % "; ".join(cluster.leftovers))
    except ClusterUnavailable as e:
        print("SKIP: " + e.reason)
        return SKIP
    except Failure as e:
        test.check(False, str(e))
    except subprocess.TimeoutExpired as e:
        test.check(False, "timed out: %s" % e)
    except KeyboardInterrupt as e:   # SIGINT, or SIGTERM while the cluster ran (it stopped)
        print("INTERRUPTED (%s)" % (e or "SIGINT"))
        return 130
    except Exception:   # noqa: BLE001 - a bug in the test or an unexpected error: a failure
        import traceback
        traceback.print_exc()
        test.check(False, "unexpected error (traceback above)")

    print("== summary")
    for what, s in test.timings:
        print("  %-48s %6.2f s" % (what, s))
    print("  %-48s %6.2f s" % ("total", time.monotonic() - t0))
    if test.failures:
        print("FAILED: %d check%s" % (len(test.failures), "" if len(test.failures) == 1 else "s"))
        for f in test.failures:
            print("  - " + f.replace("\n", "\n    "))
        return 1
    print("PASSED")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""A throw-away one-node Slurm cluster in a temporary folder, for tests and benchmarks.

    from slurm_cluster import SlurmCluster, ClusterUnavailable
    with SlurmCluster(workdir, cpus=2, memory_mb=8000) as cluster:
        out = cluster.run(["sbatch", "--parsable", "--wrap", "hostname"]).stdout
        cluster.wait_queue_empty()

It starts munged, slurmctld and slurmd in the foreground as children of this process (each
with PR_SET_PDEATHSIG, so a killed test takes them down too), all their files in a fresh
folder `<workdir>/cluster.XXXXXX/` and on free TCP ports, and points the clients at them
through `cluster.env` (SLURM_CONF). Stopping cancels every job, shuts the daemons down and
then makes sure nothing of the cluster is left running: a process whose command line mentions
the cluster folder, or whose environment names its slurm.conf (slurmstepd and the jobs'
processes), is killed and reported in `cluster.leftovers`; leaving the `with` block with
leftovers raises ClusterLeftovers. SIGTERM and SIGINT of this process unwind the `with`
block, so the cluster stops on them too.

Needs root, munge (munged) and slurm 22.05's slurmctld, slurmd and clients (Debian 12:
packages munge slurmctld slurmd slurm-client). Anything missing, or daemons that do not
come up, raise ClusterUnavailable with a one-line reason (a test should skip on it).
"""

import ctypes
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

__all__ = ["SlurmCluster", "ClusterUnavailable", "ClusterLeftovers"]

_DAEMONS = ("munged", "slurmctld", "slurmd")
_CLIENTS = ("sbatch", "squeue", "scancel", "sinfo", "scontrol")
_PR_SET_PDEATHSIG = 1


class ClusterUnavailable(Exception):
    """The cluster cannot run here: a missing binary, not root, or a daemon that did not start."""

    def __init__(self, reason):
        super().__init__(reason)
        self.reason = reason


class ClusterLeftovers(AssertionError):
    """Processes of the cluster (daemons, slurmstepd, jobs) still ran after it stopped."""


def _die_with_parent():
    """preexec_fn: the child gets SIGTERM when this process dies (even by SIGKILL)."""
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)


def _free_ports(n):
    """n distinct free TCP ports on 127.0.0.1 (bound at once, so they differ)."""
    socks = []
    try:
        for _ in range(n):
            s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            s.bind(("127.0.0.1", 0))
            socks.append(s)
        return [s.getsockname()[1] for s in socks]
    finally:
        for s in socks:
            s.close()


def _tail(path, lines=3):
    """The last non-empty lines of a file, joined with ' | ' (for one-line reasons)."""
    try:
        with open(path, "rb") as f:
            f.seek(0, os.SEEK_END)
            f.seek(max(0, f.tell() - 8192))
            text = f.read().decode("utf-8", "replace")
    except OSError:
        return "(no log)"
    kept = [ln.strip() for ln in text.splitlines() if ln.strip()][-lines:]
    return " | ".join(kept) if kept else "(empty log)"


def _proc_read(pid, name):
    try:
        with open("/proc/%d/%s" % (pid, name), "rb") as f:
            return f.read()
    except OSError:
        return None


def _proc_describe(pid):
    cmd = _proc_read(pid, "cmdline") or b""
    cmd = cmd.replace(b"\0", b" ").decode("utf-8", "replace").strip()
    if not cmd:
        comm = _proc_read(pid, "comm") or b"?"
        cmd = "[%s]" % comm.decode("utf-8", "replace").strip()
    return "pid %d: %s" % (pid, cmd[:200])


class SlurmCluster:
    """A one-node cluster (node `localhost`, partition `test`) of `cpus` CPUs and `memory_mb` MB."""

    def __init__(self, workdir, cpus=2, memory_mb=8000, start_timeout=30.0, kill_wait=5,
                 scheduler_parameters=None, verbose=False):
        self.workdir = os.path.abspath(workdir)
        self.cpus = int(cpus)
        self.memory_mb = int(memory_mb)
        self.start_timeout = float(start_timeout)
        self.kill_wait = int(kill_wait)
        # slurm.conf's SchedulerParameters, e.g. "batch_sched_delay=0" (Slurm's default 3 s
        # delays the start of batch jobs, array tasks included, to a 3 s cadence)
        self.scheduler_parameters = scheduler_parameters
        self.verbose = verbose
        self.root = None          # the cluster's folder
        self.conf = None          # its slurm.conf
        self.env = None           # environment for the clients (and vdb_ewa submit/status)
        self.leftovers = []       # descriptions of processes killed at stop
        self.partition = "test"
        self.node = "localhost"
        self._procs = {}          # name -> Popen
        self.munge_socket = None
        self._socket_dir = None   # a folder in /tmp for munge's socket where the root's path cannot hold it
        self._old_handlers = {}
        self._stopped = True
        self.stale = []           # processes of earlier clusters in workdir killed at start

    # ---- context manager -------------------------------------------------------------------
    def __enter__(self):
        self.start()
        return self

    def __exit__(self, exc_type, exc, tb):
        leftovers = self.stop()
        if leftovers and exc_type is None:
            raise ClusterLeftovers("cluster processes left running after stop (killed): "
                                   + "; ".join(leftovers))
        return False

    # ---- helpers for the caller ------------------------------------------------------------
    def run(self, args, check=False, timeout=60, **kwargs):
        """subprocess.run(args) with the cluster's environment, text output captured."""
        kwargs.setdefault("stdout", subprocess.PIPE)
        kwargs.setdefault("stderr", subprocess.PIPE)
        kwargs.setdefault("universal_newlines", True)
        return subprocess.run(args, env=self.env, check=check, timeout=timeout, **kwargs)

    def queue(self, job_id=None):
        """squeue lines 'JOBID STATE' (array tasks one a line) of job_id, or of every job."""
        args = ["squeue", "-h", "-r", "-o", "%i %T"]
        if job_id is not None:
            args += ["-j", str(job_id)]
        r = self.run(args, timeout=30)
        if r.returncode != 0:
            # squeue -j of a job that has already left slurmctld's records is an error
            if "Invalid job id" in r.stderr:
                return []
            raise RuntimeError("squeue failed (exit %d): %s" % (r.returncode, r.stderr.strip()))
        return [ln.strip() for ln in r.stdout.splitlines() if ln.strip()]

    def wait_queue_empty(self, job_id=None, timeout=300.0, poll=0.2):
        """Wait until job_id (or every job) has left the queue; False on timeout."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if not self.queue(job_id):
                return True
            time.sleep(poll)
        return False

    def cancel_all(self):
        self.run(["scancel", "--user=%s" % _user_name()], timeout=30)

    # ---- start -----------------------------------------------------------------------------
    def start(self):
        self.check_prerequisites()
        os.makedirs(self.workdir, exist_ok=True)
        self.stale = _kill_stale_clusters(self.workdir)
        if self.stale and self.verbose:
            print("slurm_cluster: killed processes of an earlier cluster in %s: %s"
                  % (self.workdir, "; ".join(self.stale)), file=sys.stderr)
        self.root = tempfile.mkdtemp(prefix="cluster.", dir=self.workdir)
        os.chmod(self.root, 0o755)
        self._stopped = False
        self._install_signal_handlers()
        try:
            self._start_munge()
            last = None
            for _attempt in range(3):   # a port taken between picking and binding: pick again
                try:
                    self._start_slurm()
                    return
                except _PortClash as e:
                    last = e
                    self._stop_slurm_daemons(wait_first=False)
            raise ClusterUnavailable("slurm daemons could not bind their ports: %s" % last)
        except BaseException:
            self.stop()
            raise

    @staticmethod
    def check_prerequisites():
        """Raise ClusterUnavailable when this machine cannot run the cluster (cheap: no start)."""
        if sys.platform != "linux":
            raise ClusterUnavailable("needs Linux")
        missing = [b for b in _DAEMONS + _CLIENTS if shutil.which(b, path=_search_path()) is None]
        if missing:
            raise ClusterUnavailable("missing binaries: %s (Debian: apt-get install munge slurmctld "
                                     "slurmd slurm-client)" % " ".join(missing))
        if os.geteuid() != 0:
            raise ClusterUnavailable("slurmd must run as root (uid is %d)" % os.geteuid())

    def _start_munge(self):
        # munged wants its key private (a 0700 folder, mode 0400) and its socket's folder
        # open to all (clients of any user connect to it)
        mdir = os.path.join(self.root, "munge")
        os.mkdir(mdir)
        os.chmod(mdir, 0o755)
        kdir = os.path.join(mdir, "key")
        os.mkdir(kdir, 0o700)
        os.chmod(kdir, 0o700)
        key = os.path.join(kdir, "munge.key")
        fd = os.open(key, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o400)
        with os.fdopen(fd, "wb") as f:
            f.write(os.urandom(1024))
        os.chmod(key, 0o400)
        sock = os.path.join(mdir, "munge.socket")
        # sun_path holds 108 bytes, and munged wants every folder above its socket searchable
        # by all (a CI's checkout under mktemp -d is not): else a short folder in /tmp
        if len(sock.encode()) > 100 or not _searchable_by_all(mdir):
            self._socket_dir = tempfile.mkdtemp(prefix="vdbmunge.", dir="/tmp")
            os.chmod(self._socket_dir, 0o755)
            sock = os.path.join(self._socket_dir, "munge.socket")
        self.munge_socket = sock
        log = os.path.join(mdir, "munged.log")
        self._spawn("munged", ["munged", "-F", "--key-file=" + key, "--socket=" + sock,
                               "--pid-file=" + os.path.join(mdir, "munged.pid"),
                               "--log-file=" + log,
                               "--seed-file=" + os.path.join(mdir, "munged.seed")],
                    os.path.join(mdir, "munged.out"))
        end = time.monotonic() + 10
        while not os.path.exists(sock):
            if self._procs["munged"].poll() is not None:
                raise ClusterUnavailable("munged exited (%d): %s" % (
                    self._procs["munged"].returncode,
                    _tail(log) + " / " + _tail(os.path.join(mdir, "munged.out"))))
            if time.monotonic() > end:
                raise ClusterUnavailable("munged did not create its socket in 10 s: " + _tail(log))
            time.sleep(0.05)

    def _write_conf(self, ctld_port, slurmd_port):
        r = self.root
        for d in ("state", "spool", "log"):
            os.makedirs(os.path.join(r, d), exist_ok=True)
        plugstack = os.path.join(r, "plugstack.conf")   # not /etc/slurm's: nothing of the host's
        open(plugstack, "w").close()
        lines = [
            "ClusterName=vdbtest",
            "SlurmctldHost=localhost(127.0.0.1)",
            "SlurmctldPort=%d" % ctld_port,
            "SlurmdPort=%d" % slurmd_port,
            "AuthType=auth/munge",
            "AuthInfo=socket=%s" % self.munge_socket,
            "CredType=cred/munge",
            "SlurmUser=root",
            "SlurmdUser=root",
            "StateSaveLocation=%s/state" % r,
            "SlurmdSpoolDir=%s/spool" % r,
            "SlurmctldPidFile=%s/slurmctld.pid" % r,
            "SlurmdPidFile=%s/slurmd.pid" % r,
            "SlurmctldLogFile=%s/log/slurmctld.log" % r,
            "SlurmdLogFile=%s/log/slurmd.log" % r,
            "SlurmctldDebug=info",
            "SlurmdDebug=info",
            "PlugStackConfig=%s" % plugstack,
            "ProctrackType=proctrack/linuxproc",
            "TaskPlugin=task/none",
            "JobAcctGatherType=jobacct_gather/none",
            "AccountingStorageType=accounting_storage/none",
            "JobCompType=jobcomp/none",
            "SelectType=select/cons_tres",
            "SelectTypeParameters=CR_CPU_Memory",
            "SchedulerType=sched/backfill",
        ] + (["SchedulerParameters=%s" % self.scheduler_parameters]
             if self.scheduler_parameters else []) + [
            "SlurmdParameters=config_overrides",
            "ReturnToService=2",
            "MpiDefault=none",
            # SIGTERM -> SIGKILL delay of a cancelled job; short timeouts for a local cluster
            "KillWait=%d" % self.kill_wait,
            "MessageTimeout=5",
            "SlurmdTimeout=60",
            "InactiveLimit=0",
            "MinJobAge=300",
            "NodeName=%s NodeAddr=127.0.0.1 CPUs=%d RealMemory=%d State=UNKNOWN"
            % (self.node, self.cpus, self.memory_mb),
            "PartitionName=%s Nodes=%s Default=YES MaxTime=INFINITE State=UP"
            % (self.partition, self.node),
        ]
        self.conf = os.path.join(r, "slurm.conf")
        with open(self.conf, "w") as f:
            f.write("\n".join(lines) + "\n")

    def _start_slurm(self):
        ctld_port, slurmd_port = _free_ports(2)
        self._write_conf(ctld_port, slurmd_port)
        self.env = _clean_env()
        self.env["SLURM_CONF"] = self.conf
        log = os.path.join(self.root, "log")
        for name in ("slurmctld.log", "slurmd.log"):
            # a retry's daemons must not find the previous attempt's lines
            if os.path.exists(os.path.join(log, name)):
                os.rename(os.path.join(log, name), os.path.join(log, name + ".old"))
        self._spawn("slurmctld", ["slurmctld", "-D", "-f", self.conf],
                    os.path.join(log, "slurmctld.out"))
        self._spawn("slurmd", ["slurmd", "-D", "-f", self.conf, "-N", self.node],
                    os.path.join(log, "slurmd.out"))
        end = time.monotonic() + self.start_timeout
        state = ""
        while True:
            for name in ("slurmctld", "slurmd"):
                p = self._procs[name]
                if p.poll() is not None:
                    text = _tail(os.path.join(log, name + ".log")) + " / " + _tail(
                        os.path.join(log, name + ".out"))
                    if "Address already in use" in text:
                        raise _PortClash(name + ": " + text)
                    raise ClusterUnavailable("%s exited (%d) at start: %s"
                                             % (name, p.returncode, text))
            r = self.run(["sinfo", "-h", "-o", "%t"], timeout=20)
            state = (r.stdout.strip() or r.stderr.strip()).splitlines()
            state = state[0] if state else ""
            if r.returncode == 0 and state == "idle":
                return
            if time.monotonic() > end:
                raise ClusterUnavailable(
                    "node not idle after %.0f s (sinfo: %r); slurmctld.log: %s; slurmd.log: %s"
                    % (self.start_timeout, state, _tail(os.path.join(log, "slurmctld.log")),
                       _tail(os.path.join(log, "slurmd.log"))))
            time.sleep(0.2)

    def _spawn(self, name, args, out_path):
        env = _clean_env()
        if self.conf:
            env["SLURM_CONF"] = self.conf
        out = open(out_path, "ab")
        try:
            self._procs[name] = subprocess.Popen(
                args, cwd=self.root, env=env, stdin=subprocess.DEVNULL, stdout=out, stderr=out,
                preexec_fn=_die_with_parent, start_new_session=True)
        except OSError as e:
            raise ClusterUnavailable("cannot start %s: %s" % (name, e))
        finally:
            out.close()

    # ---- stop ------------------------------------------------------------------------------
    def stop(self):
        """Stop everything; return (and keep in self.leftovers) the processes that had to be
        killed after the orderly shutdown. Safe to call twice."""
        if self._stopped:
            return self.leftovers
        self._stopped = True
        self._ignore_signals()   # a second Ctrl-C must not cut the clean-up short
        notes = []
        shutdown_sent = False
        try:
            ctld_up = "slurmctld" in self._procs and self._procs["slurmctld"].poll() is None
            if ctld_up and self.env:
                try:
                    self.cancel_all()
                    # the jobs' processes get SIGTERM, then SIGKILL after KillWait
                    if not self.wait_queue_empty(timeout=self.kill_wait + 20):
                        notes.append("jobs still in the queue %d s after scancel: %s"
                                     % (self.kill_wait + 20, " ".join(self.queue())))
                except (OSError, subprocess.SubprocessError, RuntimeError) as e:
                    notes.append("scancel: %s" % e)
                try:
                    r = self.run(["scontrol", "shutdown"], timeout=20)
                    shutdown_sent = r.returncode == 0
                    if not shutdown_sent:
                        notes.append("scontrol shutdown failed: %s" % r.stderr.strip())
                except (OSError, subprocess.SubprocessError) as e:
                    notes.append("scontrol shutdown: %s" % e)
            self._stop_slurm_daemons(notes, wait_first=shutdown_sent)
            self._stop_process("munged", notes, wait_first=False)
        finally:
            self.leftovers = self._kill_leftovers() + notes
            self._restore_signal_handlers()
            if self._socket_dir:
                shutil.rmtree(self._socket_dir, ignore_errors=True)
        return self.leftovers

    def _stop_slurm_daemons(self, notes=None, wait_first=True):
        for name in ("slurmd", "slurmctld"):
            self._stop_process(name, notes, wait_first=wait_first)

    def _stop_process(self, name, notes, timeout=15.0, wait_first=True):
        p = self._procs.pop(name, None)
        if p is None:
            return
        if wait_first:
            try:
                p.wait(timeout=timeout)   # after scontrol shutdown the slurm daemons exit
                return
            except subprocess.TimeoutExpired:
                if notes is not None:
                    notes.append("%s still ran %.0f s after scontrol shutdown" % (name, timeout))
        p.terminate()
        try:
            p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
            if notes is not None:
                notes.append("%s ignored SIGTERM and was killed" % name)

    def cluster_processes(self):
        """pids of processes that belong to this cluster: their command line mentions its folder,
        or their environment names its slurm.conf (slurmstepd, job scripts and their children)."""
        if not self.root:
            return []
        marks = [self.root.encode()]
        if self._socket_dir:
            marks.append(self._socket_dir.encode())
        env_mark = ("SLURM_CONF=%s" % self.conf).encode() if self.conf else None
        me = os.getpid()
        found = []
        for entry in os.listdir("/proc"):
            if not entry.isdigit():
                continue
            pid = int(entry)
            if pid == me:
                continue
            cmd = _proc_read(pid, "cmdline")
            if cmd is None:
                continue
            hit = any(m in cmd for m in marks)
            if not hit and env_mark:
                environ = _proc_read(pid, "environ") or b""
                hit = any(v == env_mark for v in environ.split(b"\0"))
            if hit and not _is_zombie(pid):
                found.append(pid)
        return found

    def _kill_leftovers(self):
        pids = self.cluster_processes()
        described = _kill_described(pids)
        end = time.monotonic() + 5
        while time.monotonic() < end and any(_alive(p) for p in pids):
            time.sleep(0.05)
        return described

    # ---- signals ---------------------------------------------------------------------------
    def _install_signal_handlers(self):
        import threading
        if threading.current_thread() is not threading.main_thread():
            return

        def handler(signum, frame):
            # unwind the caller's `with` block (and any wait) so stop() runs
            raise KeyboardInterrupt("signal %d" % signum)

        for sig in (signal.SIGTERM, signal.SIGINT):
            try:
                self._old_handlers[sig] = signal.signal(sig, handler)
            except (ValueError, OSError):
                pass

    def _ignore_signals(self):
        for sig in list(self._old_handlers):
            try:
                signal.signal(sig, signal.SIG_IGN)
            except (ValueError, OSError):
                pass

    def _restore_signal_handlers(self):
        for sig, old in self._old_handlers.items():
            try:
                signal.signal(sig, old)
            except (ValueError, OSError, TypeError):
                pass
        self._old_handlers = {}


def _kill_stale_clusters(workdir):
    """Kill what is left of earlier clusters in workdir whose slurmctld is gone: a test killed
    with SIGKILL takes its daemons with it (PR_SET_PDEATHSIG) but not the slurmstepd of its
    running jobs, which wait for their slurmd for ever. Returns their descriptions."""
    prefix = os.path.join(workdir, "cluster.").encode()
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == os.getpid():
            continue
        pid = int(entry)
        cmd = _proc_read(pid, "cmdline") or b""
        environ = _proc_read(pid, "environ") or b""
        roots = set()
        for text in [cmd] + [v for v in environ.split(b"\0") if v.startswith(b"SLURM_CONF=")]:
            i = text.find(prefix)
            if i >= 0:
                rest = text[i + len(prefix):]
                roots.add(prefix + rest.split(b"/")[0].split(b"\0")[0].split(b" ")[0])
        for root in roots:
            if not _slurmctld_alive(root.decode("utf-8", "replace")) and not _is_zombie(pid):
                found.append(pid)
                break
    return _kill_described(found)


def _kill_described(pids):
    """SIGKILL pids; returns what they were."""
    described = [_proc_describe(p) for p in pids]
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    return described


def _searchable_by_all(path):
    """True if every folder from / to path has execute permission for all."""
    path = os.path.abspath(path)
    while True:
        try:
            if not os.stat(path).st_mode & 0o001:
                return False
        except OSError:
            return False
        parent = os.path.dirname(path)
        if parent == path:
            return True
        path = parent


def _slurmctld_alive(root):
    try:
        with open(os.path.join(root, "slurmctld.pid")) as f:
            pid = int(f.read().strip())
    except (OSError, ValueError):
        return False
    cmd = _proc_read(pid, "cmdline") or b""
    return b"slurmctld" in cmd and root.encode() in cmd


class _PortClash(Exception):
    pass


def _search_path():
    return os.environ.get("PATH", "") + ":/usr/sbin:/sbin:/usr/bin:/bin:/usr/local/sbin"


def _clean_env():
    """This process's environment without SLURM_* (a test run inside a Slurm job must not
    leak the outer job's variables into ours), with sbin on PATH for the daemons."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("SLURM_")}
    env["PATH"] = _search_path()
    return env


def _user_name():
    import pwd
    return pwd.getpwuid(os.geteuid()).pw_name


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return not _is_zombie(pid)


def _is_zombie(pid):
    stat = _proc_read(pid, "stat")
    if not stat:
        return True
    # the state follows the command name in parentheses, which may itself hold ')'
    return stat[stat.rfind(b")") + 2:stat.rfind(b")") + 3] in (b"Z", b"X")


def _self_test(workdir):
    """Start a cluster, run an array job, cancel a running job (one that ignores SIGTERM too),
    leave one running for stop() to cancel, and check nothing is left."""
    t0 = time.monotonic()
    with SlurmCluster(workdir) as c:
        print("cluster up in %s (%.2f s)" % (c.root, time.monotonic() - t0))
        out = os.path.join(c.root, "job_%A_%a.out")
        r = c.run(["sbatch", "--parsable", "--array=0-2", "-c", "1", "--mem=100M", "-o", out,
                   "--wrap", "env | grep ^SLURM | sort; sleep 2"], check=True)
        job = r.stdout.strip()
        t = time.monotonic()
        assert c.wait_queue_empty(job, timeout=60), "array job did not finish"
        print("array job %s (3 tasks of 2 s, 2 CPUs) left the queue in %.2f s"
              % (job, time.monotonic() - t))
        for task in range(3):
            with open(os.path.join(c.root, "job_%s_%d.out" % (job, task))) as f:
                text = f.read()
            assert "SLURM_ARRAY_TASK_ID=%d\n" % task in text, text
            assert "SLURM_CPUS_PER_TASK=1\n" in text and "SLURM_MEM_PER_NODE=100\n" in text, text
        r = c.run(["sbatch", "--parsable", "-c", "1", "--mem=100M", "-o", "/dev/null",
                   "--wrap", "trap '' TERM; sleep 300"], check=True)
        stubborn = r.stdout.strip()
        r = c.run(["sbatch", "--parsable", "-c", "1", "--mem=100M", "-o", "/dev/null",
                   "--wrap", "sleep 301"], check=True)
        left = r.stdout.strip()
        end = time.monotonic() + 30
        while not all(c.queue(j) and c.queue(j)[0].endswith("RUNNING") for j in (stubborn, left)):
            assert time.monotonic() < end, "jobs did not start: %s" % c.queue()
            time.sleep(0.2)
        t = time.monotonic()
        c.run(["scancel", stubborn], check=True)
        assert c.wait_queue_empty(stubborn, timeout=60)
        print("job %s ignoring SIGTERM cancelled in %.2f s (KillWait %d s)"
              % (stubborn, time.monotonic() - t, c.kill_wait))
        assert not any(b"sleep\x00300" in (_proc_read(p, "cmdline") or b"")
                       for p in c.cluster_processes()), "the cancelled job's sleep still runs"
        t = time.monotonic()
    print("stopped with job %s running in %.2f s; leftovers: %s"
          % (left, time.monotonic() - t, c.leftovers or "none"))


if __name__ == "__main__":
    # Smoke test: python3 slurm_cluster.py WORKDIR
    import argparse
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("workdir")
    a = ap.parse_args()
    try:
        _self_test(a.workdir)
    except ClusterUnavailable as e:
        print("SKIP:", e.reason)
        sys.exit(77)

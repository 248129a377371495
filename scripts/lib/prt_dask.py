"""prt_dask: what the Dask front ends share (issue 21): scripts/prt-batch (many scans, one task per
file and step) and scripts/prt-bricks-dask (one large scan's bricked build, one task per group of
octree cells). A local cluster by default, --scheduler's otherwise; tools run as child processes
that die with their worker; a tool's one error line as the reason of a failure.

Python 3 from Debian (/usr/bin/python3) with python3-distributed and python3-dask; python3-psutil
to stop a local cluster's processes at once on Ctrl-C.
"""
import ctypes
import logging
import os
import shutil
import subprocess
import tempfile


class UsageError(Exception):
    """A bad command line, a missing tool or scheduler: exit status 2."""


def find_bin_dir(bin_dir, tool, here):
    """The folder holding `tool`: `bin_dir` when given, else $PRT_BIN_DIR, else the scripts' folder
    `here` when it holds the tool, else ../build/bin next to it, else the PATH's. Raises UsageError
    when none holds it."""
    if bin_dir:
        return os.path.abspath(bin_dir)
    if os.environ.get("PRT_BIN_DIR"):
        return os.path.abspath(os.environ["PRT_BIN_DIR"])
    for d in (here, os.path.join(here, "..", "build", "bin")):
        if os.access(os.path.join(d, tool), os.X_OK):
            return os.path.abspath(d)
    if shutil.which(tool):
        return os.path.dirname(os.path.abspath(shutil.which(tool)))
    raise UsageError("%s not found (give --bin-dir, set PRT_BIN_DIR or add it to the PATH)" % tool)


def tool_version(path):
    """The tool's --version line, or None when it cannot say."""
    try:
        p = subprocess.run([path, "--version"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, timeout=60)
        return p.stdout.decode("utf-8", "replace").strip() or None
    except (OSError, subprocess.TimeoutExpired):
        return None


def die_with_parent():
    """A preexec_fn for a tool's process: SIGKILL when the worker thread that started it dies
    (Linux PR_SET_PDEATHSIG), so a killed worker does not leave its tool running and writing.
    libc is loaded here, before the fork (dlopen between fork and exec could wait on a lock that
    another thread held)."""
    try:
        prctl = ctypes.CDLL("libc.so.6", use_errno=True).prctl
    except (OSError, AttributeError):
        return None
    return lambda: prctl(1, 9)  # PR_SET_PDEATHSIG, SIGKILL


def reason(log_text, tool, status):
    """The tool's one error line ("prt-import: error: ..."), else its last line."""
    lines = [l for l in log_text.replace("\r", "\n").splitlines() if l.strip()]
    errors = [l for l in lines if ": error: " in l]
    line = errors[-1] if errors else (lines[-1] if lines else "")
    if status < 0:
        line = "%s killed by signal %d%s" % (tool, -status, " (last output: %s)" % line if line else "")
    elif not line:
        line = "%s failed with exit status %d and no message" % (tool, status)
    return line[:400]


def own_error(status, why):
    """Whether a tool's failure is its own error on its input (exit 1 or 2 with a "TOOL: error:"
    line, `why` from reason()): the same input gives the same answer, so it is not retried."""
    return status in (1, 2) and ": error: " in why


def one_line(e):
    """A task's exception as one line (Dask's KilledWorker: the workers running it died)."""
    name = type(e).__name__
    if name == "KilledWorker":
        return "the worker running it died, and so did those that ran it again (%s)" % str(e).strip()[:300]
    text = str(e).strip().splitlines()
    return (text[-1] if text else name)[:400]


def start_client(prog, jobs, scheduler, state, by_value=()):
    """A Dask client: on `scheduler`'s cluster, else on a new local cluster of `jobs` processes (one
    thread each). Modules in `by_value` are sent to the workers with the tasks (workers need not
    find scripts/lib). Returns (client, cluster or None); state["scratch"] gets dask's temporary
    folder (the caller removes it)."""
    logging.getLogger("distributed").setLevel(logging.ERROR)
    try:
        import cloudpickle
        import dask
        from distributed import Client, LocalCluster
    except ImportError as e:
        raise UsageError("%s: install Debian's python3-dask and python3-distributed "
                         "(scripts/install-deps.sh) and run with /usr/bin/python3" % e)
    import sys

    for module in (sys.modules[__name__],) + tuple(by_value):
        cloudpickle.register_pickle_by_value(module)
    if scheduler:
        try:
            return Client(scheduler, timeout="20s"), None
        except (OSError, TimeoutError) as e:
            raise UsageError("no Dask scheduler at %s: %s" % (scheduler, e))
    scratch = state["scratch"] = tempfile.mkdtemp(prefix=prog + "-dask.")
    dask.config.set({"temporary-directory": scratch, "distributed.logging.distributed": "error"})
    cluster = LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True, memory_limit=0,
                           dashboard_address=":0", silence_logs=logging.ERROR, scheduler_port=0,
                           local_directory=scratch)
    return Client(cluster), cluster


def dashboard(client):
    """The dashboard's address, or None (Debian 12 packages no bokeh, which serves it)."""
    try:
        import bokeh  # noqa: F401
    except ImportError:
        return None
    try:
        return client.dashboard_link
    except Exception:  # noqa: BLE001 - an address is a nicety
        return None


def kill_children():
    """Kills this process's descendants (a local cluster's nannies and workers, the tools they run)
    and waits for them, so that no step finishes after an interruption."""
    try:
        import psutil
    except ImportError:
        return
    children = psutil.Process().children(recursive=True)
    for child in children:
        try:
            child.kill()
        except psutil.Error:
            pass
    psutil.wait_procs(children, timeout=5)

"""scripts/prt-batch on Dask (issue 21): a local cluster of 3 worker processes against a serial run
of the tools, a worker killed mid-task, resuming. Run by ctest (prt_batch_dask_test) with Debian's
python3 (dask, distributed, pytest); PRT_BIN_DIR names the tools, PRT_BATCH the script."""
import json
import math
import os
import signal
import subprocess
import sys
import time

import pytest

BIN = os.environ.get("PRT_BIN_DIR", "")
BATCH = os.environ.get("PRT_BATCH", os.path.join(os.path.dirname(__file__), "..", "..", "scripts", "prt-batch"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(BATCH)), "lib"))
import prt_provenance  # noqa: E402

STEPS = ["import", "radii", "octree"]
BAD = {  # name: content, the reasons prt-import may give (one of them)
    "empty.off": (b"", ("prt-import: error: ",)),
    "truncated.ply": (b"ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
                      b"property float z\nend_header\n1 2 3\n", ("header declares 5 vertices but the data ends after 1",)),
    # PCL finds no header; a build without PCL refuses every PCD file, naming what it lacks
    "garbage.pcd": (b"not a point cloud\n", ("not a valid PCD file", "PCD import needs PCL")),
    "binary.xyz": (b"\x00\x01\x02binary", ("binary data, not XYZ text",)),
}


def tool(name):
    path = os.path.join(BIN, name)
    if not os.access(path, os.X_OK):
        pytest.skip("%s not built (PRT_BIN_DIR=%r)" % (name, BIN))
    return path


def sphere_xyz(path, n, scale=1.0, phase=0.0):
    """n points on a sphere of radius `scale` (golden-angle spiral) with outward normals: a
    reference scan whose conversion is known to succeed."""
    g = math.pi * (3 - math.sqrt(5))
    with open(path, "w") as f:
        for i in range(n):
            y = 1 - 2 * (i + 0.5) / n
            r = math.sqrt(1 - y * y)
            t = g * i + phase
            x, z = r * math.cos(t), r * math.sin(t)
            f.write("%.7f %.7f %.7f %.7f %.7f %.7f\n" % (scale * x, scale * y, scale * z, x, y, z))


def make_scans(folder, good=16):
    os.makedirs(folder, exist_ok=True)
    names = []
    for i in range(good):
        name = "scan%02d.xyz" % i
        sphere_xyz(os.path.join(folder, name), 300 + 37 * i, 1.0 + 0.1 * i, 0.01 * i)
        names.append(name)
    for name, (data, _) in BAD.items():
        with open(os.path.join(folder, name), "wb") as f:
            f.write(data)
    return names


def batch(*args, timeout=300):
    p = subprocess.run([BATCH, "-b", BIN, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout)
    return p.returncode, p.stdout.decode(), p.stderr.decode()


def serial(src, dst):
    """The reference: the tools one after the other, by hand."""
    subprocess.run([tool("prt-import"), src, "-o", dst + ".i", "-q"], check=True)
    subprocess.run([tool("prt-radii"), dst + ".i", "-o", dst + ".r", "-q"], check=True)
    subprocess.run([tool("prt-octree"), dst + ".r", "-o", dst, "-q"], check=True)


def valid(pool):
    return subprocess.run([tool("prt-info"), pool], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode == 0


def leftovers(folder):
    """Files and folders other than the outputs (work folders, temporary pools)."""
    out = []
    for root, dirs, files in os.walk(folder):
        out += [os.path.join(root, d) for d in dirs if d.startswith(".prt-batch")]
        out += [os.path.join(root, f) for f in files if not f.endswith(".pool") or ".tmp" in f]
    return out


@pytest.fixture(scope="module")
def scans(tmp_path_factory):
    for t in ("prt-import", "prt-radii", "prt-octree", "prt-info"):
        tool(t)
    folder = str(tmp_path_factory.mktemp("scans"))
    return folder, make_scans(folder)


def test_cluster_equals_serial_and_lists_the_bad_files(scans, tmp_path):
    src, good = scans
    out = str(tmp_path / "out")
    code, summary, progress = batch("-j", "3", "-t", "1", "-s", ",".join(STEPS), src, out)
    assert code == 1, summary + progress  # the bad files failed
    assert "20 files in %s: 16 ok, 4 failed, 0 skipped" % src in summary
    assert "3 workers x 1 threads" in summary
    for name, (_, reason) in BAD.items():
        line = [l for l in summary.splitlines() if l.startswith("  failed  %s: " % os.path.join(src, name))]
        assert len(line) == 1 and any(r in line[0] for r in reason), summary
        assert not os.path.exists(os.path.join(out, os.path.splitext(name)[0] + ".pool"))
    assert len([l for l in progress.splitlines() if l.startswith("prt-batch: [")]) == 20
    assert "Dask dashboard: " in progress
    ref = str(tmp_path / "ref")
    os.makedirs(ref)
    for name in good:
        stem = os.path.splitext(name)[0]
        serial(os.path.join(src, name), os.path.join(ref, stem + ".pool"))
        got = prt_provenance.read_sections(os.path.join(out, stem + ".pool"))
        want = prt_provenance.read_sections(os.path.join(ref, stem + ".pool"))
        assert sorted(got) == sorted(want), name
        for t in want:
            assert got[t] == want[t], "%s: section %d differs from the serial run's" % (name, t)
        # The provenance names the chain, with the input's content hash in the last step's tag.
        prov = prt_provenance.read_provenance(os.path.join(out, stem + ".pool"))
        assert [p["tool"] for p in prov[-3:]] == ["prt-import", "prt-radii", "prt-octree"]
        assert prov[-1]["parameters"]["tag"]["input"] == prt_provenance.file_hash(os.path.join(src, name))
    assert leftovers(out) == []


def test_a_killed_worker_loses_nothing(tmp_path):
    for t in ("prt-import", "prt-info"):
        tool(t)
    src = str(tmp_path / "in")
    make_scans(src, good=5)
    big = os.path.join(src, "big.xyz")
    sphere_xyz(big, 400000)
    out = str(tmp_path / "out")
    p = subprocess.Popen([BATCH, "-b", BIN, "-j", "3", "-t", "1", src, out], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE)
    try:
        # The worker that runs prt-import on the big scan: the tool's parent process.
        deadline, first = time.time() + 120, None
        while first is None and time.time() < deadline and p.poll() is None:
            first = pids_of(big) or None
            time.sleep(0.01)
        assert first, "prt-import on the big scan never ran"
        tool_pid = first[0]
        worker = parent_of(tool_pid)
        assert worker != p.pid  # a worker process, not prt-batch itself
        os.kill(worker, signal.SIGKILL)
        # The tool dies with its worker; the task runs again (a new prt-import on the same file).
        again = None
        while again is None and time.time() < deadline and p.poll() is None:
            again = [q for q in pids_of(big) if q != tool_pid] or None
            time.sleep(0.01)
        stdout, stderr = p.communicate(timeout=240)
    finally:
        if p.poll() is None:
            p.kill()
    summary = stdout.decode()
    assert not os.path.exists("/proc/%d" % tool_pid) or open("/proc/%d/stat" % tool_pid).read().split()[2] == "Z"
    assert again, "the killed task was not run again\n" + summary
    assert "ok      %s" % big in summary, summary
    assert "1 worker(s) lost during the run; Dask ran their tasks again" in summary
    assert "lost with " in stderr.decode() and big in stderr.decode()
    assert p.returncode == 1, summary + stderr.decode()
    assert "10 files in %s: 6 ok, 4 failed, 0 skipped" % src in summary, summary + stderr.decode()
    for f in os.listdir(src):
        stem = os.path.splitext(f)[0]
        if f not in BAD:
            assert valid(os.path.join(out, stem + ".pool")), f
    assert leftovers(out) == []


def command_lines():
    """(pid, argv as bytes) of every process that can be read."""
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                yield int(d), open("/proc/%s/cmdline" % d, "rb").read().split(b"\0")
            except OSError:
                continue


def pids_of(path):
    return [pid for pid, cmd in command_lines()
            if len(cmd) > 1 and cmd[0].endswith(b"prt-import") and path.encode() in cmd]


def parent_of(pid):
    with open("/proc/%d/stat" % pid) as f:
        return int(f.read().rsplit(")", 1)[1].split()[1])


def test_resume_does_nothing_then_only_the_changed_chain(tmp_path):
    tool("prt-import")
    src = str(tmp_path / "in")
    names = make_scans(src, good=6)
    for name in BAD:
        os.remove(os.path.join(src, name))
    out = str(tmp_path / "out")
    code, summary, _ = batch("-j", "2", "-s", "import,radii", src, out)
    assert code == 0 and "6 ok, 0 failed, 0 skipped" in summary, summary
    pools = {n: os.path.join(out, os.path.splitext(n)[0] + ".pool") for n in names}
    before = {n: os.stat(p).st_mtime_ns for n, p in pools.items()}
    code, summary, _ = batch("-j", "2", "-s", "import,radii", src, out)
    assert code == 0 and "0 ok, 0 failed, 6 skipped" in summary, summary
    assert "nothing to do: every output is current" in summary
    assert {n: os.stat(p).st_mtime_ns for n, p in pools.items()} == before
    # New content (the modification time alone would not do: the check is the content's hash).
    sphere_xyz(os.path.join(src, names[2]), 500, 3.0)
    code, summary, _ = batch("-j", "2", "-s", "import,radii", src, out)
    assert code == 0 and "1 ok, 0 failed, 5 skipped" in summary, summary
    assert "ok      %s -> %s" % (os.path.join(src, names[2]), pools[names[2]]) in summary
    after = {n: os.stat(p).st_mtime_ns for n, p in pools.items()}
    assert [n for n in names if after[n] != before[n]] == [names[2]]
    # Other parameters are another result; --force redoes everything.
    code, summary, _ = batch("-j", "2", "-s", "import,radii", "--radii-args", "-k 6", src, out)
    assert code == 0 and "6 ok, 0 failed, 0 skipped" in summary, summary
    code, summary, _ = batch("-j", "2", "-s", "import,radii", "--radii-args", "-k 6", "--force", src, out)
    assert code == 0 and "6 ok, 0 failed, 0 skipped" in summary, summary
    assert leftovers(out) == []


def crashing_tools(folder, crashes):
    """A bin folder whose prt-import dies of SIGSEGV `crashes` times, then runs the real one."""
    os.makedirs(folder)
    fake = os.path.join(folder, "prt-import")
    with open(fake, "w") as f:
        f.write("#!/bin/bash\n[ \"$1\" = --version ] && exec '%s' --version\n"
                "n=$(cat '%s/count' 2>/dev/null || echo 0); echo $((n + 1)) >'%s/count'\n"
                "if [ $n -lt %d ]; then echo 'about to crash' >&2; kill -SEGV $$; fi\n"
                "exec '%s' \"$@\"\n" % (tool("prt-import"), folder, folder, crashes, tool("prt-import")))
    os.chmod(fake, 0o755)
    return folder


def test_a_crashing_step_is_retried_then_reported(tmp_path):
    src = str(tmp_path / "in")
    os.makedirs(src)
    sphere_xyz(os.path.join(src, "one.xyz"), 300)
    # Two crashes, two retries: the third run succeeds.
    bin2 = crashing_tools(str(tmp_path / "bin2"), 2)
    p = subprocess.run([BATCH, "-b", bin2, "-j", "1", "--retries", "2", src, str(tmp_path / "out2")],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=300)
    summary = p.stdout.decode()
    assert p.returncode == 0 and "1 ok, 0 failed" in summary, summary + p.stderr.decode()
    assert open(os.path.join(bin2, "count")).read().strip() == "3"
    assert valid(str(tmp_path / "out2" / "one.pool"))
    # Three crashes, one retry: reported after two runs with the signal and the tool's last line.
    bin3 = crashing_tools(str(tmp_path / "bin3"), 3)
    p = subprocess.run([BATCH, "-b", bin3, "-j", "1", "--retries", "1", src, str(tmp_path / "out3")],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=300)
    summary = p.stdout.decode()
    assert p.returncode == 1, summary
    assert "failed  %s: prt-import killed by signal 11 (last output: about to crash)" % os.path.join(src, "one.xyz") in summary
    assert open(os.path.join(bin3, "count")).read().strip() == "2"
    assert leftovers(str(tmp_path / "out3")) == []


def test_current_reason_names_what_differs(tmp_path):
    """scripts/lib/prt_provenance.py's skip decision on a pool written with a tag by prt-import."""
    src = str(tmp_path / "a.xyz")
    sphere_xyz(src, 200)
    digest = prt_provenance.file_hash(src)
    assert digest.startswith(prt_provenance.hash_name() + ":")
    tag = prt_provenance.chain_tag(digest, ["prt-import"], {"prt-import": ["--normals", "keep"]})
    pool = str(tmp_path / "a.pool")
    version = subprocess.run([tool("prt-import"), "--version"], stdout=subprocess.PIPE).stdout.decode().strip()
    assert prt_provenance.current_reason(pool, [{"tool": "prt-import", "version": version, "tag": tag}]) == "no output yet"
    subprocess.run([tool("prt-import"), src, "-o", pool, "-q", "--normals", "keep", "--provenance-tag",
                    prt_provenance.json_text(tag)], check=True)
    want = {"tool": "prt-import", "version": version, "tag": tag}
    assert prt_provenance.current_reason(pool, [want]) is None
    other_input = dict(want, tag=dict(tag, input="xxh3_64:0"))
    assert prt_provenance.current_reason(pool, [other_input]) == "the input changed (content hash differs)"
    other_args = dict(want, tag=dict(tag, args={"prt-import": []}))
    assert prt_provenance.current_reason(pool, [other_args]) == "prt-import ran with other parameters"
    assert "version" in prt_provenance.current_reason(pool, [dict(want, version="0.0-other")])
    longer = [want, {"tool": "prt-radii", "version": version, "tag": tag}]
    assert "provenance has 1 steps, the chain has 2" in prt_provenance.current_reason(pool, longer)
    with open(str(tmp_path / "junk.pool"), "wb") as f:
        f.write(b"junk")
    assert "bad magic" in prt_provenance.current_reason(str(tmp_path / "junk.pool"), [want])
    # Changing one byte of the input changes the hash.
    with open(src, "r+b") as f:
        f.seek(3)
        c = f.read(1)
        f.seek(3)
        f.write(b"7" if c != b"7" else b"8")
    assert prt_provenance.file_hash(src) != digest


def test_an_existing_cluster_through_scheduler(tmp_path):
    """The several-machines path of the README on one machine: `dask scheduler`, `dask worker
    ADDRESS` (2 processes), then prt-batch --scheduler ADDRESS."""
    tool("prt-import")
    dask_cli = os.path.join(os.path.dirname(os.path.realpath(sys.executable)), "dask")
    if not os.access(dask_cli, os.X_OK):
        pytest.skip("no dask command beside %s" % sys.executable)
    src = str(tmp_path / "in")
    names = make_scans(src, good=4)
    info = str(tmp_path / "scheduler.json")
    procs = []
    try:
        procs.append(subprocess.Popen([dask_cli, "scheduler", "--port", "0", "--dashboard-address", ":0",
                                       "--scheduler-file", info], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        deadline = time.time() + 60
        while not os.path.exists(info) and time.time() < deadline:
            time.sleep(0.1)
        time.sleep(0.2)
        address = json.load(open(info))["address"]
        procs.append(subprocess.Popen([dask_cli, "worker", address, "--nworkers", "2", "--nthreads", "1",
                                       "--local-directory", str(tmp_path / "dask")],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        from distributed import Client

        with Client(address, timeout="30s") as c:  # both worker processes joined
            c.wait_for_workers(2, timeout=60)
        code, summary, progress = batch("--scheduler", address, src, str(tmp_path / "out"))
        assert code == 1, summary + progress
        assert "8 files in %s: 4 ok, 4 failed, 0 skipped" % src in summary, summary + progress
        assert "on %s (2 workers x 1 threads)" % address in progress
        for n in names:
            assert valid(str(tmp_path / "out" / (os.path.splitext(n)[0] + ".pool")))
        assert leftovers(str(tmp_path / "out")) == []
    finally:
        for p in reversed(procs):
            p.terminate()
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()

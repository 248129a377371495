"""scripts/prt-bricks-dask (issue 21): one scan's bricked build split into octree cells across a
local Dask cluster of 3 worker processes equals prt-bricks in one process byte for byte; a worker
killed while it builds cells loses nothing; a second run does nothing; bad input is one line. Run
by ctest (prt_bricks_dask_test) with Debian's python3; PRT_BIN_DIR names the tools, PRT_BRICKS_DASK
the script."""
import math
import os
import signal
import subprocess
import sys
import time

from test_prt_batch_dask import command_lines, parent_of, sphere_xyz, tool, valid  # noqa: E402  (this folder)

BIN = os.environ.get("PRT_BIN_DIR", "")
SCRIPT = os.environ.get("PRT_BRICKS_DASK",
                        os.path.join(os.path.dirname(__file__), "..", "..", "scripts", "prt-bricks-dask"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(SCRIPT)), "lib"))
import prt_provenance  # noqa: E402

# Small cells, so that even a small model is cut into many (the default cuts by --memory).
ARGS = "--cell-points 3000 --brick-splats 2000 --backend cpu"


def radii_pool(folder, n):
    """A sphere of n points through prt-import and prt-radii: the input prt-bricks builds from."""
    xyz = os.path.join(folder, "scan.xyz")
    sphere_xyz(xyz, n)
    imported, pool = os.path.join(folder, "scan.i.pool"), os.path.join(folder, "scan.pool")
    subprocess.run([tool("prt-import"), xyz, "-o", imported, "-q"], check=True)
    subprocess.run([tool("prt-radii"), imported, "-o", pool, "-q"], check=True)
    os.remove(imported)
    os.remove(xyz)
    return pool


def reference(pool, out):
    subprocess.run([tool("prt-bricks"), pool, "-o", out, "-q", "-j", "2"] + ARGS.split(), check=True)


def run(*args, timeout=300):
    p = subprocess.run([SCRIPT, "-b", BIN, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout)
    return p.returncode, p.stdout.decode(), p.stderr.decode()


def same_sections(a, b):
    sa, sb = prt_provenance.read_sections(a), prt_provenance.read_sections(b)
    assert sorted(sa) == sorted(sb)
    for t in sa:
        assert sa[t] == sb[t], "section %d differs" % t


def test_cells_on_a_cluster_equal_one_process_and_resume(tmp_path):
    pool = radii_pool(str(tmp_path), 40000)
    ref = str(tmp_path / "ref.pool")
    reference(pool, ref)
    out = str(tmp_path / "out" / "scan.pool")
    code, stdout, stderr = run(pool, "-o", out, "-j", "3", "-t", "1", "--cells-per-task", "2", "--bricks-args", ARGS)
    assert code == 0, stdout + stderr
    assert "ok %s -> %s" % (pool, out) in stdout
    cells = int(stdout.split("(")[1].split(" cells")[0])
    assert cells >= 8, stdout  # the model was cut into many cells
    assert "planned %d cells" % cells in stderr
    same_sections(ref, out)
    prov = prt_provenance.read_provenance(out)
    assert [p["tool"] for p in prov[-3:]] == ["prt-import", "prt-radii", "prt-bricks"]
    assert prov[-1]["parameters"]["tag"]["input"] == prt_provenance.file_hash(pool)
    assert os.listdir(tmp_path / "out") == ["scan.pool"]  # no work folder, no part left behind
    # A second run does nothing; other options build again.
    code, stdout, _ = run(pool, "-o", out, "-j", "2", "--bricks-args", ARGS)
    assert code == 0 and "skipped" in stdout and "is current" in stdout, stdout
    code, stdout, stderr = run(pool, "-o", out, "-j", "2", "--bricks-args", ARGS + " --lod-splats 16")
    assert code == 0 and "ok " in stdout, stdout + stderr


def test_a_killed_worker_loses_nothing(tmp_path):
    pool = radii_pool(str(tmp_path), 150000)
    ref = str(tmp_path / "ref.pool")
    reference(pool, ref)
    out = str(tmp_path / "out.pool")
    work = str(tmp_path / "work")
    p = subprocess.Popen([SCRIPT, "-b", BIN, pool, "-o", out, "-j", "3", "-t", "1", "--work", work,
                          "--bricks-args", ARGS], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    killed = None
    try:
        deadline = time.time() + 120
        while killed is None and time.time() < deadline and p.poll() is None:
            cells = cells_pids(pool)
            if cells:
                try:
                    worker = parent_of(cells[0][0])
                except OSError:  # it finished meanwhile: look again
                    continue
                if worker != p.pid:
                    os.kill(worker, signal.SIGKILL)  # the worker running a cells task
                    killed = cells[0]
            time.sleep(0.01)
        try:
            stdout, stderr = p.communicate(timeout=240)
        except subprocess.TimeoutExpired:  # say where it hung: the run's output so far
            p.kill()
            stdout, stderr = p.communicate()
            raise AssertionError("prt-bricks-dask did not finish in 240 s after the kill of %s:\n%s%s" % (
                killed, stdout.decode(), stderr.decode()))
    finally:
        if p.poll() is None:
            p.kill()
    assert killed, "no cells task was seen running"
    assert p.returncode == 0, stdout.decode() + stderr.decode()
    same_sections(ref, out)
    assert not os.path.exists(work)
    assert valid(out)


def cells_pids(pool):
    """(pid, cells) of the prt-bricks processes building cells of `pool`."""
    return [(pid, cmd[cmd.index(b"--cells") + 1].decode()) for pid, cmd in command_lines()
            if cmd[0].endswith(b"prt-bricks") and pool.encode() in cmd and b"--cells" in cmd]


def test_bad_input_is_one_line(tmp_path):
    xyz = str(tmp_path / "scan.xyz")
    with open(xyz, "w") as f:  # points without normals, imported without estimating them
        for i in range(2000):
            f.write("%f %f %f\n" % (math.cos(i * 0.1), math.sin(i * 0.1), i * 1e-3))
    imported = str(tmp_path / "scan.pool")
    subprocess.run([tool("prt-import"), xyz, "-o", imported, "-q", "--normals", "keep"], check=True)
    out = str(tmp_path / "out.pool")
    code, stdout, stderr = run(imported, "-o", out, "-j", "2")
    assert code == 1, stdout + stderr
    assert stdout.strip().startswith("prt-bricks-dask: failed: prt-bricks: error: %s: no octree and no normals" % imported), stdout
    assert not os.path.exists(out)
    assert os.listdir(tmp_path) == ["scan.xyz", "scan.pool"] or sorted(os.listdir(tmp_path)) == ["scan.pool", "scan.xyz"]
    code, _, stderr = run(imported, "-o", out, "--bricks-args", "--stage plan")
    assert code == 2 and "must not hold --stage" in stderr, stderr
    code, _, stderr = run(str(tmp_path / "missing.pool"), "-o", out)
    assert code == 2 and "does not exist" in stderr, stderr

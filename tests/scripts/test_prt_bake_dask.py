"""scripts/prt-bake with several scenes on Dask (issue 21): a local cluster of 3 workers bakes four
scenes that share a pool, equal to baking them one after the other; a bad scene and a scene whose
caustic map would replace another's are reported and the others go on; the shared pool is built
once; a second run does nothing; a changed source reruns only its chain and the passes of the
scenes that place it; a worker killed mid-step loses nothing. Run by ctest (prt_bake_dask_test)
with Debian's python3 (dask, distributed, pytest); PRT_BIN_DIR names the tools, PRT_BAKE the
script."""
import math
import os
import shutil
import signal
import subprocess
import sys
import time

import pytest

BIN = os.environ.get("PRT_BIN_DIR", "")
BAKE = os.environ.get("PRT_BAKE", os.path.join(os.path.dirname(__file__), "..", "..", "scripts", "prt-bake"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(BAKE)), "lib"))
import prt_provenance  # noqa: E402
from test_prt_batch_dask import command_lines, parent_of  # noqa: E402  (this folder)

TOOLS = ["prt-import", "prt-radii", "prt-octree", "prt-cull", "prt-iso", "prt-mls", "prt-photons",
         "prt-lightmap", "prt-info"]
S_PROVENANCE = 1

GLASS = ('{"name": "glass", "transmissivity": 0.9, "diffuse_reflectance": 0.1, "refractive_index": 1.5}')
SCENES = {
    # caustics: the room (shared) under a glass ball
    "a.json": '{"materials": [{"name": "wall"}, %s], "models": ['
              '{"name": "room", "source": "room.ply", "pool": "pools/room.pool", "material": "wall"},'
              '{"name": "ball", "source": "ball.ply", "pool": "pools/ball.pool", "material": "glass"}],'
              '"lights": [{"type": "point", "position": [0, 2, 0]}], "render": {"caustics": true}}' % GLASS,
    # a light map: the room and an ISO object
    "b.json": '{"models": [{"name": "room", "source": "room.ply", "pool": "pools/room.pool"},'
              '{"name": "obj", "source": "obj.ply", "pool": "pools/obj.pool", "surface": "iso"}],'
              '"lights": [{"type": "point", "position": [0, 2, 0]}], "render": {"light_map": true}}',
    # an MLS object alone
    "c.json": '{"models": [{"name": "blob", "source": "blob.ply", "pool": "pools/blob.pool", "surface": "mls"}]}',
    # the room alone
    "d.json": '{"models": [{"name": "room", "source": "room.ply", "pool": "pools/room.pool"}]}',
}
# A model without its source; a second caustic map into the room (a.json's would be replaced).
BAD = {
    "bad.json": ('{"models": [{"name": "ghost", "source": "nothere.ply"}]}', "model 'ghost': source "),
    "e.json": (SCENES["a.json"].replace("ball.p", "obj.p").replace('"ball"', '"lens"'),
               "prt-photons would write pool %s's caustics, which a.json's prt-photons writes too"),
}


def tool(name):
    path = os.path.join(BIN, name)
    if not os.access(path, os.X_OK):
        pytest.skip("%s not built (PRT_BIN_DIR=%r)" % (name, BIN))
    return path


def sphere_ply(path, n, scale=1.0):
    """n points on a sphere (golden-angle spiral) with outward normals, as an ASCII PLY."""
    g = math.pi * (3 - math.sqrt(5))
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
                "property float nx\nproperty float ny\nproperty float nz\nend_header\n" % n)
        for i in range(n):
            y = 1 - 2 * (i + 0.5) / n
            r = math.sqrt(1 - y * y)
            x, z = r * math.cos(g * i), r * math.sin(g * i)
            f.write("%.7f %.7f %.7f %.7f %.7f %.7f\n" % (scale * x, scale * y, scale * z, x, y, z))


def make_scenes(folder, bad=True):
    os.makedirs(folder, exist_ok=True)
    sphere_ply(os.path.join(folder, "room.ply"), 3000, 3.0)
    sphere_ply(os.path.join(folder, "ball.ply"), 800, 0.5)
    sphere_ply(os.path.join(folder, "obj.ply"), 900, 0.4)
    sphere_ply(os.path.join(folder, "blob.ply"), 700, 0.6)
    texts = dict(SCENES)
    if bad:
        texts.update({k: v[0] for k, v in BAD.items()})
    for name, text in texts.items():
        with open(os.path.join(folder, name), "w") as f:
            f.write(text)
    return [os.path.join(folder, n) for n in texts]


def bake(*args, cwd=None, timeout=400):
    p = subprocess.run([BAKE, "-B", os.path.dirname(BIN), *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       timeout=timeout, cwd=cwd)
    return p.returncode, p.stdout.decode(), p.stderr.decode()


def leftovers(folder):
    return [os.path.join(r, f) for r, _, fs in os.walk(folder) for f in fs if ".tmp." in f]


def pools(folder):
    d = os.path.join(folder, "pools")
    return sorted(f for f in os.listdir(d) if f.endswith(".pool"))


@pytest.fixture(scope="module", autouse=True)
def tools():
    for t in TOOLS:
        tool(t)


def test_scenes_on_three_workers_equal_baking_them_one_by_one(tmp_path):
    src = str(tmp_path / "dask")
    names = make_scenes(src)
    code, summary, progress = bake("--workers", "3", *names)
    assert code == 1, summary + progress  # the two bad scenes
    assert "6 scenes: 4 baked, 0 current, 2 failed" in summary, summary + progress
    for n in SCENES:
        assert "  baked   %s" % os.path.join(src, n) in summary
    room = os.path.join(src, "pools", "room.pool")
    for n, (_, why) in BAD.items():
        line = [l for l in summary.splitlines() if l.startswith("  failed  %s: " % os.path.join(src, n))]
        assert len(line) == 1 and (why % room if "%s" in why else why) in line[0], summary
        assert "prt-bake: error: %s: " % os.path.join(src, n) in progress
    assert "(3 workers x " in progress
    # The room, placed by three scenes, imported once.
    prov = prt_provenance.read_provenance(room)
    assert [p["tool"] for p in prov].count("prt-import") == 1, prov
    assert [p["tool"] for p in prov].count("prt-octree") == 1, prov
    assert leftovers(src) == []
    # The reference: the same scenes baked one after the other by prt-bake without Dask.
    ref = str(tmp_path / "serial")
    make_scenes(ref, bad=False)
    for n in SCENES:
        code, out, err = bake("-q", os.path.join(ref, n))
        assert code == 0, out + err
    assert pools(src) == pools(ref) == ["ball.pool", "blob.pool", "obj.pool", "room.pool"]
    for pool in pools(ref):
        got = prt_provenance.read_sections(os.path.join(src, "pools", pool))
        want = prt_provenance.read_sections(os.path.join(ref, "pools", pool))
        assert sorted(got) == sorted(want), pool
        for t in want:
            if t != S_PROVENANCE:
                assert got[t] == want[t], "%s: section %d differs from the serial bake's" % (pool, t)
    # Both scenes' passes wrote the room, one after the other: a.json's caustics (none land on
    # the room's walls: the ball holds them) and b.json's light map.
    tools = [p["tool"] for p in prt_provenance.read_provenance(room)]
    assert tools[-2:] in (["prt-photons", "prt-lightmap"], ["prt-lightmap", "prt-photons"]), tools
    assert any(80 <= t <= 95 for t in prt_provenance.read_checksums(room))
    assert any(64 <= t <= 79 for t in prt_provenance.read_checksums(os.path.join(src, "pools", "ball.pool")))


def test_second_run_does_nothing_then_a_changed_source_reruns_its_chain(tmp_path):
    src = str(tmp_path / "s")
    names = make_scenes(src, bad=False)
    code, summary, progress = bake("--workers", "2", *names)
    assert code == 0 and "4 scenes: 4 baked, 0 current, 0 failed" in summary, summary + progress
    stamps = {p: os.stat(os.path.join(src, "pools", p)).st_mtime_ns for p in pools(src)}
    code, summary, progress = bake("--workers", "2", *names)
    assert code == 0 and "4 scenes: 0 baked, 4 current, 0 failed" in summary, summary + progress
    assert "nothing to do: every step the scenes need is current" in summary
    assert "steps to run" not in progress  # no cluster started
    assert {p: os.stat(os.path.join(src, "pools", p)).st_mtime_ns for p in pools(src)} == stamps
    # New content for the ball: its chain and a.json's photons run; nothing else.
    sphere_ply(os.path.join(src, "ball.ply"), 850, 0.5)
    code, summary, progress = bake("--workers", "2", *names)
    assert code == 0 and "4 scenes: 1 baked, 3 current, 0 failed" in summary, summary + progress
    ran = sorted(l.split("] ", 1)[1] for l in progress.splitlines() if " done (" in l)
    assert [r.split(" done")[0] for r in ran] == [
        "model 'ball': prt-cull", "model 'ball': prt-import", "model 'ball': prt-octree",
        "model 'ball': prt-radii", "scene a.json: prt-photons"], progress
    after = {p: os.stat(os.path.join(src, "pools", p)).st_mtime_ns for p in pools(src)}
    assert [p for p in pools(src) if after[p] != stamps[p]] == ["ball.pool", "room.pool"]  # photons: the room's map
    # Usage: --jobs is for one scene without Dask.
    code, _, err = bake("--jobs", "2", *names)
    assert code == 2 and "--jobs is for one scene without Dask" in err


def test_a_killed_worker_loses_nothing(tmp_path):
    src = str(tmp_path / "k")
    names = make_scenes(src, bad=False)
    big = os.path.join(src, "room.ply")
    sphere_ply(big, 400000, 3.0)
    p = subprocess.Popen([BAKE, "-B", os.path.dirname(BIN), "--workers", "3", "-q"] + names,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        deadline, first = time.time() + 120, None
        while first is None and time.time() < deadline and p.poll() is None:
            first = [pid for pid, cmd in command_lines()
                     if len(cmd) > 1 and cmd[0].endswith(b"prt-import") and big.encode() in cmd] or None
            time.sleep(0.01)
        assert first, "prt-import of the room never ran"
        worker = parent_of(first[0])
        assert worker != p.pid
        os.kill(worker, signal.SIGKILL)
        stdout, stderr = p.communicate(timeout=300)
    finally:
        if p.poll() is None:
            p.kill()
    summary = stdout.decode()
    assert p.returncode == 0, summary + stderr.decode()
    assert "4 scenes: 4 baked, 0 current, 0 failed" in summary, summary
    for pool in pools(src):
        assert subprocess.run([tool("prt-info"), os.path.join(src, "pools", pool)], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL).returncode == 0, pool
    assert leftovers(src) == []
    code, summary, _ = bake("--workers", "2", *names)
    assert code == 0 and "0 baked, 4 current" in summary, summary
    shutil.rmtree(src)

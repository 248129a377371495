# pytest fixtures for the Python module (issue 18): sphere pools made by the tools (prt-synth,
# prt-radii, prt-octree) from PRT_BIN_DIR; the module from PYTHONPATH (ctest sets both).
import os
import subprocess

import pytest

BIN = os.environ.get("PRT_BIN_DIR", "")


def make_sphere(directory, name, points=20000, extra=()):
    """A unit sphere (prt-synth) sampled with `points` points, splats built (radii, octree)."""
    tool = lambda t: os.path.join(BIN, t)
    if not all(os.path.exists(tool(t)) for t in ("prt-synth", "prt-radii", "prt-octree")):
        pytest.skip("prt-synth, prt-radii or prt-octree not built (PRT_BIN_DIR=%r)" % BIN)
    raw, radii, out = (os.path.join(directory, name + s) for s in (".synth.pool", ".radii.pool", ".pool"))
    subprocess.run([tool("prt-synth"), "sphere", "-n", str(points), "-o", raw, "-q", *extra], check=True)
    subprocess.run([tool("prt-radii"), raw, "-o", radii, "-q"], check=True)
    subprocess.run([tool("prt-octree"), radii, "-o", out, "-q"], check=True)
    return out


@pytest.fixture(scope="session")
def sphere_pool(tmp_path_factory):
    return make_sphere(str(tmp_path_factory.mktemp("sphere")), "sphere")


@pytest.fixture(scope="session")
def far_sphere_pool(tmp_path_factory):
    """The unit sphere a million units from the world origin (double precision at the boundary)."""
    return make_sphere(str(tmp_path_factory.mktemp("far")), "far", extra=("--offset", "1000000,-2000000,500000"))


@pytest.fixture(scope="session")
def surface_pools(tmp_path_factory, sphere_pool):
    """The sphere pool with ISO and MLS sections added, and a bricked copy; a kind whose tool is
    not built is left out."""
    d = str(tmp_path_factory.mktemp("surfaces"))
    tool = lambda t: os.path.join(BIN, t)
    pools = {}
    if os.path.exists(tool("prt-iso")) and os.path.exists(tool("prt-mls")):
        p = os.path.join(d, "iso_mls.pool")
        subprocess.run([tool("prt-iso"), sphere_pool, "-o", p, "-q"], check=True)
        subprocess.run([tool("prt-mls"), p, "-o", p, "-q"], check=True)
        pools["iso"] = pools["mls"] = p
    if os.path.exists(tool("prt-bricks")):
        p = os.path.join(d, "bricked.pool")
        subprocess.run([tool("prt-bricks"), sphere_pool, "-o", p, "--brick-splats", "4000", "-q"], check=True)
        pools["bricks"] = p
    return pools

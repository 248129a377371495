# The Python module against analytic answers (issue 18): rays cast at a unit sphere sampled by
# prt-synth, compared with the exact ray-sphere intersection; misses, occlusion, invalid rays,
# render shape and dtype, argument errors. Label cpu (the CPU backend).
import numpy as np
import pytest

pointrt = pytest.importorskip("pointrt")


def sphere_rays(n, seed, centre=(0.0, 0.0, 0.0)):
    """Rays from points on a sphere of radius 3 toward random points inside radius 0.8 (all hit)."""
    rng = np.random.default_rng(seed)
    o = rng.normal(size=(n, 3))
    o *= 3.0 / np.linalg.norm(o, axis=1, keepdims=True)
    target = rng.normal(size=(n, 3))
    target *= (0.8 * rng.random((n, 1)) ** (1 / 3)) / np.linalg.norm(target, axis=1, keepdims=True)
    d = target - o
    return o + np.asarray(centre), d


def analytic_t(o, d, centre=(0.0, 0.0, 0.0), r=1.0):
    """First root of |o + t d - c| = r (t in units of |d|)."""
    oc = o - np.asarray(centre)
    a = np.sum(d * d, axis=1)
    b = 2 * np.sum(oc * d, axis=1)
    c = np.sum(oc * oc, axis=1) - r * r
    return (-b - np.sqrt(b * b - 4 * a * c)) / (2 * a)


def test_hits_match_the_analytic_sphere(sphere_pool):
    s = pointrt.open(sphere_pool, backend="cpu")
    o, d = sphere_rays(2000, 1)
    h = s.cast(o, d)
    assert h["hit"].dtype == np.bool_ and h["t"].dtype == np.float32 and h["element"].dtype == np.int64
    assert h["hit"].all() and h["valid"].all()
    t_ref = analytic_t(o, d)
    dist_err = np.abs(h["t"] - t_ref) * np.linalg.norm(d, axis=1)  # in distance units
    # 20k points on the unit sphere: spacing ~0.025; blended splats sit within a small fraction of it.
    assert np.median(dist_err) < 1e-3 and dist_err.max() < 3e-3, (np.median(dist_err), dist_err.max())
    p_ref = o + t_ref[:, None] * d
    n = h["normal"]
    assert np.allclose(np.linalg.norm(n, axis=1), 1, atol=1e-4)
    cos = np.sum(n * p_ref, axis=1)  # the sphere's normal at p is p
    assert cos.min() > 0.999, cos.min()
    assert np.abs(np.linalg.norm(h["position"], axis=1) - 1).max() < 1e-2
    assert (h["model"] == 0).all()
    assert (h["element"] >= 0).all() and (h["element"] < 20000).all()


def test_t_range_and_direction_length(sphere_pool):
    s = pointrt.open(sphere_pool, backend="cpu")
    o = np.array([[0.0, 0.0, 3.0]])
    for scale in (1.0, 0.25, 10.0):
        h = s.cast(o, np.array([[0.0, 0.0, -scale]]))
        assert h["hit"][0] and abs(h["t"][0] * scale - 2.0) < 5e-3
    # t_max before the sphere: a miss; t_min past the front: the ray starts inside and the
    # back face is not a front face (seamless rays), so it misses too.
    assert not s.cast(o, np.array([0.0, 0.0, -1.0]), t_max=1.9)["hit"][0]
    assert s.cast(o, np.array([0.0, 0.0, -1.0]), t_max=2.1)["hit"][0]
    h = s.cast(o, np.array([0.0, 0.0, -1.0]), t_min=np.array([1.0], dtype=np.float32))
    assert h["hit"][0] and abs(h["t"][0] - 2.0) < 5e-3


def test_miss_and_invalid_rays(sphere_pool):
    s = pointrt.open(sphere_pool, backend="cpu")
    o = np.array([[0, 0, 3], [0, 0, 3], [np.nan, 0, 0], [0, 0, 3], [0, 0, np.inf]], dtype=np.float64)
    d = np.array([[0, 1, 0], [0, 0, 1], [0, 0, -1], [0, 0, 0], [0, 0, -1]], dtype=np.float64)
    h = s.cast(o, d)
    assert not h["hit"].any()
    assert h["valid"].tolist() == [True, True, False, False, False]
    assert np.isinf(h["t"]).all() and (h["model"] == -1).all() and (h["element"] == -1).all()
    assert not np.isnan(h["position"]).any() and not np.isnan(h["normal"]).any()
    assert not s.occluded(o, d).any()


def test_occlusion(sphere_pool):
    s = pointrt.open(sphere_pool, backend="cpu")
    a = np.array([0.0, 0.0, 3.0])  # one origin for every ray: shape (3,)
    b = np.array([[0, 0, -3], [3, 0, 0], [0, 3, 0], [0, 0.5, -3]], dtype=np.float32)
    blocked = s.occluded(a, b - a, t_max=0.999)
    assert blocked.dtype == np.bool_
    assert blocked.tolist() == [True, False, False, True]
    # Against the analytic answer: the segment a-b passes within radius 1 of the centre.
    rng = np.random.default_rng(7)
    b = rng.uniform(-3, 3, size=(500, 3))
    b = b[np.abs(np.linalg.norm(b, axis=1) - 1) > 0.1]  # keep end points off the surface
    d = b - a
    t = np.clip(-np.sum(a * d, axis=1) / np.sum(d * d, axis=1), 0, 1)
    closest = np.linalg.norm(a + t[:, None] * d, axis=1)
    inside_b = np.linalg.norm(b, axis=1) < 1
    ref = (closest < 1) & ~inside_b  # b inside: the ray meets the front face first
    ref |= inside_b
    got = s.occluded(a, d, t_max=1.0)
    clear = np.abs(closest - 1) > 0.02  # grazing segments: the splat discs decide
    assert (got[clear] == ref[clear]).all()


def test_far_from_the_origin(far_sphere_pool):
    s = pointrt.open(far_sphere_pool, backend="cpu")
    c = (1000000.0, -2000000.0, 500000.0)
    o, d = sphere_rays(500, 2, centre=c)
    h = s.cast(o, d)  # float64 origins: converted to the render frame in double
    assert h["hit"].all()
    err = np.abs(h["t"] - analytic_t(o, d, centre=c)) * np.linalg.norm(d, axis=1)
    assert err.max() < 3e-3, err.max()


def test_float32_and_strided_inputs(sphere_pool):
    s = pointrt.open(sphere_pool, backend="cpu")
    o, d = sphere_rays(300, 3)
    ref = s.cast(o, d)["t"]
    both = np.concatenate([o, d], axis=1).astype(np.float32)  # (N, 6): strided views
    h = s.cast(both[:, :3], both[:, 3:])
    assert np.allclose(h["t"], ref, atol=1e-4)
    h = s.cast(o, d, fields=["t"])
    assert list(h) == ["t"]


def test_out_arrays(sphere_pool):
    s = pointrt.open(sphere_pool, backend="cpu")
    o, d = sphere_rays(100, 4)
    t = np.empty(100, dtype=np.float32)
    h = s.cast(o, d, out={"t": t}, fields=["t", "hit"])
    assert h["t"] is t and np.isfinite(t).all()
    with pytest.raises(TypeError, match="out\\['t'\\]"):
        s.cast(o, d, out={"t": np.empty(100, dtype=np.float64)}, fields=["t"])


def test_render_shape_and_dtype(sphere_pool):
    img = pointrt.render(sphere_pool, width=40, height=30, backend="cpu")
    assert img.shape == (30, 40, 4) and img.dtype == np.uint8
    s = pointrt.open(sphere_pool, backend="cpu")
    img = s.render(eye=(0, 0, 4), look_at=(0, 0, 0), width=32, height=32)
    assert img.shape == (32, 32, 4)
    # The sphere fills the centre, the background the corners.
    assert not np.array_equal(img[16, 16], img[0, 0])


def test_errors(sphere_pool, tmp_path):
    with pytest.raises(pointrt.Error, match="no such file"):
        pointrt.open(str(tmp_path / "missing.pool"))
    bad = tmp_path / "bad.pool"
    bad.write_bytes(b"not a pool at all")
    with pytest.raises(pointrt.Error) as e:
        pointrt.open(str(bad), backend="cpu")
    assert "\n" not in str(e.value) and "bad.pool" in str(e.value)
    with pytest.raises(pointrt.Error, match="backend"):
        pointrt.open(sphere_pool, backend="warp-drive")
    with pytest.raises(pointrt.Error):
        pointrt.open(sphere_pool, backend="cpu", surface="iso")  # the pool has no ISO sections
    s = pointrt.open(sphere_pool, backend="cpu")
    with pytest.raises(ValueError, match="origins"):
        s.cast(np.zeros((4, 2)), np.zeros((4, 3)))
    with pytest.raises(ValueError, match="directions"):
        s.cast(np.zeros((4, 3)), np.zeros((4, 3, 1)))
    with pytest.raises(ValueError, match="origins, directions"):
        s.cast(np.zeros((4, 3)), np.zeros((5, 3)))
    with pytest.raises(TypeError, match="origins"):
        s.cast(np.array([["a", "b", "c"]]), np.zeros((1, 3)))
    with pytest.raises(ValueError, match="t_max"):
        s.cast(np.zeros((4, 3)), np.ones((4, 3)), t_max=np.ones(3))
    with pytest.raises(ValueError, match="fields"):
        s.cast(np.zeros((4, 3)), np.ones((4, 3)), fields=["depth"])
    assert s.cast(np.zeros((0, 3)), np.zeros((0, 3)))["t"].shape == (0,)
    assert s.occluded(np.zeros((0, 3)), np.zeros((0, 3))).shape == (0,)


def test_info_and_backends(sphere_pool):
    s = pointrt.open(sphere_pool, backend="cpu")
    assert s.backend == "cpu" and s.info["surfaces"] == ["splats"] and s.info["points"] == 20000
    assert "cpu" in pointrt.available_backends()


@pytest.mark.parametrize("kind", ["iso", "mls", "bricks"])
def test_every_surface_against_the_analytic_sphere(surface_pools, kind):
    if kind not in surface_pools:
        pytest.skip("the tool that builds %s is not built" % kind)
    surface = "" if kind == "bricks" else kind
    s = pointrt.open(surface_pools[kind], backend="cpu", surface=surface)
    assert s.info["surfaces"] == ["splats" if kind == "bricks" else kind]
    o, d = sphere_rays(1000, 21)
    h = s.cast(o, d)
    assert h["hit"].all()
    err = np.abs(h["t"] - analytic_t(o, d)) * np.linalg.norm(d, axis=1)
    assert np.median(err) < 2e-3 and err.max() < 1e-2, (kind, np.median(err), err.max())
    p_ref = o + analytic_t(o, d)[:, None] * d
    assert np.sum(h["normal"] * p_ref, axis=1).min() > 0.99
    if kind == "mls":
        assert (h["element"] >= 0).all()  # the source point of the largest weight
    if kind in ("iso", "bricks"):
        assert (h["element"] == -1).all()  # no source point
    assert s.occluded(o, d).all()


def test_patches_give_their_patch_index(tmp_path):
    # Two flat bicubic patches side by side in the plane z = 0 (seed 002's .bpt format: the count,
    # then per patch its degrees and 16 control points, evenly spaced so Q(u, v) is affine; front
    # faces look up +z): rays from z = 3 straight down meet them at t = 3 with normal +z.
    import os
    import subprocess

    tool = os.path.join(os.environ.get("PRT_BIN_DIR", ""), "prt-patches")
    if not os.path.exists(tool):
        pytest.skip("prt-patches not built")
    lines = ["2"]
    for x0 in (-2.0, 0.0):
        lines.append("3 3")
        for i in range(4):
            for j in range(4):
                lines.append("%r %r 0" % (x0 + 2.0 * i / 3, -1.0 + 2.0 * j / 3))
    bpt = tmp_path / "two.bpt"
    bpt.write_text("\n".join(lines) + "\n")
    pool = tmp_path / "two.pool"
    subprocess.run([tool, str(bpt), "-o", str(pool), "-q"], check=True)
    s = pointrt.open(str(pool), backend="cpu")
    assert s.info["surfaces"] == ["patches"]
    o = np.array([[-1.0, 0.3, 3.0], [1.0, -0.4, 3.0], [3.0, 0.0, 3.0]])
    h = s.cast(o, np.array([0.0, 0.0, -1.0]))
    assert h["hit"].tolist() == [True, True, False]
    assert np.allclose(h["t"][:2], 3.0, atol=1e-5)
    assert np.allclose(h["normal"][:2], [0, 0, 1], atol=1e-5)
    assert h["element"].tolist() == [0, 1, -1]
    assert np.allclose(h["position"][:2], [[-1.0, 0.3, 0.0], [1.0, -0.4, 0.0]], atol=1e-5)

# The Python module on the CUDA backend (issue 18), label gpu: skips without a CUDA device. Device
# arrays through __cuda_array_interface__: PyTorch tensors when torch is installed (the device has
# it), else the module's own DeviceArray; the answers equal the CPU backend's.
import numpy as np
import pytest

pointrt = pytest.importorskip("pointrt")
if "cuda" not in pointrt.available_backends():
    pytest.skip("no CUDA device (or a build without the CUDA backend)", allow_module_level=True)

from test_pointrt import analytic_t, sphere_rays  # noqa: E402


def test_host_arrays_on_the_gpu_match_the_cpu(sphere_pool):
    o, d = sphere_rays(20000, 11)
    cpu = pointrt.open(sphere_pool, backend="cpu").cast(o, d)
    gpu = pointrt.open(sphere_pool, backend="cuda").cast(o, d)
    assert (cpu["hit"] == gpu["hit"]).mean() > 0.999
    both = cpu["hit"] & gpu["hit"]
    assert np.abs(cpu["t"][both] - gpu["t"][both]).max() < 1e-3
    err = np.abs(gpu["t"] - analytic_t(o, d)) * np.linalg.norm(d, axis=1)
    assert np.median(err) < 2e-3


def test_torch_tensors_in_and_out_without_copies(sphere_pool):
    torch = pytest.importorskip("torch")
    if not torch.cuda.is_available():
        pytest.skip("torch sees no CUDA device")
    s = pointrt.open(sphere_pool, backend="cuda")
    o, d = sphere_rays(10000, 12)
    to = torch.as_tensor(o, dtype=torch.float32, device="cuda")
    td = torch.as_tensor(d, dtype=torch.float32, device="cuda")
    h = s.cast(to, td)
    t = torch.as_tensor(h["t"], device="cuda")  # a DeviceArray: zero-copy view
    assert t.shape == (10000,) and t.device.type == "cuda"
    ref = pointrt.open(sphere_pool, backend="cpu").cast(o.astype(np.float32), d.astype(np.float32))["t"]
    assert np.abs(t.cpu().numpy() - ref).max() < 1e-3
    # Caller-provided outputs are written in place.
    out_t = torch.empty(10000, dtype=torch.float32, device="cuda")
    s.cast(to, td, out={"t": out_t}, fields=["t"])
    assert torch.equal(out_t, t)
    flags = s.occluded(to, td)
    assert torch.as_tensor(flags, device="cuda").all()
    # DeviceArray's host copy.
    assert h["hit"].numpy().all() and h["position"].shape == (10000, 3)
    # float64 tensors and one origin for every ray (shape (3,)).
    h64 = s.cast(torch.as_tensor(o[0], device="cuda"), torch.as_tensor(d, device="cuda"), fields=["hit"])
    assert h64["hit"].numpy().shape == (10000,)


def test_host_arrays_give_numpy_on_the_gpu(sphere_pool):
    s = pointrt.open(sphere_pool, backend="cuda")
    o, d = sphere_rays(100, 13)
    h = s.cast(o, d)
    assert isinstance(h["t"], np.ndarray) and h["hit"].all()
    assert s.last_stats["device_ms"] > 0


def test_device_arrays_on_the_cpu_backend_fail(sphere_pool):
    torch = pytest.importorskip("torch")
    if not torch.cuda.is_available():
        pytest.skip("torch sees no CUDA device")
    s = pointrt.open(sphere_pool, backend="cpu")
    to = torch.zeros((4, 3), device="cuda")
    with pytest.raises(pointrt.Error, match="cpu backend"):
        s.cast(to, to)

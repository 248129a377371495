// PointRT's Python module (issue 18), on the public C++ API (prt/pointrt.h) with pybind11:
//
//     import numpy as np, pointrt
//     s = pointrt.open("sphere.pool", backend="cpu")
//     hits = s.cast(origins, directions, t_min=0.0, t_max=np.inf)   # dict of numpy arrays
//     blocked = s.occluded(origins, directions, t_max=1.0)           # bool array
//     image = s.render(eye=(0, 0, 5), look_at=(0, 0, 0), width=640, height=480)  # H x W x 4 uint8
//
// Host inputs: numpy arrays (or anything np.asarray takes), origins and directions (N, 3) or (3,)
// (one for every ray), float32 or float64 (other numbers are converted to float64); t_min, t_max a
// number or an (N,) array. On the CUDA backend, inputs exposing __cuda_array_interface__ (PyTorch
// tensors, CuPy arrays) are read in place, and the outputs are device arrays too: the caller's
// (`out=`) or new ones exposing __cuda_array_interface__ (torch.as_tensor(x, device="cuda") and
// cupy.asarray(x) take them without copies).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "prt/pointrt.h"

namespace py = pybind11;

namespace {

// ---- Device arrays ----------------------------------------------------------------------------------

/// Device memory from pointrt::device_malloc with a shape and a type: what cast() returns for
/// device inputs without `out`. Exposes __cuda_array_interface__ (version 3).
class DeviceArray {
public:
    DeviceArray(std::vector<std::size_t> shape, std::string typestr, std::size_t itemsize)
        : m_shape(std::move(shape)), m_typestr(std::move(typestr)), m_itemsize(itemsize) {
        m_ptr = pointrt::device_malloc(bytes());
    }
    ~DeviceArray() { pointrt::device_free(m_ptr); }
    DeviceArray(const DeviceArray&) = delete;
    DeviceArray& operator=(const DeviceArray&) = delete;

    std::size_t count() const {
        std::size_t n = 1;
        for (std::size_t s : m_shape) n *= s;
        return n;
    }
    std::size_t bytes() const { return count() * m_itemsize; }
    void* data() const { return m_ptr; }

    py::dict interface() const {
        py::dict d;
        py::tuple shape(m_shape.size());
        for (std::size_t i = 0; i < m_shape.size(); ++i) shape[i] = m_shape[i];
        d["shape"] = shape;
        d["typestr"] = m_typestr;
        d["data"] = py::make_tuple(reinterpret_cast<std::uintptr_t>(m_ptr), false);
        d["version"] = 3;
        d["strides"] = py::none();
        d["stream"] = py::none();  // the library synchronizes before it returns
        return d;
    }
    /// A host copy as a numpy array.
    py::array numpy() const {
        py::array out(py::dtype(m_typestr), std::vector<py::ssize_t>(m_shape.begin(), m_shape.end()));
        pointrt::device_to_host(out.mutable_data(), m_ptr, bytes());
        return out;
    }
    std::vector<std::size_t> shape() const { return m_shape; }

private:
    std::vector<std::size_t> m_shape;
    std::string m_typestr;
    std::size_t m_itemsize;
    void* m_ptr = nullptr;
};

/// A device array given by the caller (__cuda_array_interface__), checked.
struct DeviceView {
    void* ptr = nullptr;
    std::vector<std::size_t> shape;
    std::vector<std::size_t> strides;  ///< bytes
    std::string typestr;
    bool readonly = false;
};

bool has_cuda_interface(const py::handle& o) {
    return py::hasattr(o, "__cuda_array_interface__");
}

std::size_t itemsize_of(const std::string& typestr) {
    return typestr.size() >= 3 ? static_cast<std::size_t>(std::stoul(typestr.substr(2))) : 0;
}

DeviceView device_view(const py::handle& o, const char* name) {
    const py::dict d = o.attr("__cuda_array_interface__");
    DeviceView v;
    v.typestr = py::str(d["typestr"]);
    const py::tuple data = d["data"];
    v.ptr = reinterpret_cast<void*>(data[0].cast<std::uintptr_t>());
    v.readonly = data[1].cast<bool>();
    for (const py::handle s : py::tuple(d["shape"])) v.shape.push_back(s.cast<std::size_t>());
    const std::size_t item = itemsize_of(v.typestr);
    if (d.contains("strides") && !d["strides"].is_none()) {
        for (const py::handle s : py::tuple(d["strides"])) {
            const auto st = s.cast<long long>();
            if (st < 0) throw py::value_error(std::string(name) + ": negative strides are not supported");
            v.strides.push_back(static_cast<std::size_t>(st));
        }
    } else {
        v.strides.resize(v.shape.size());
        std::size_t st = item;
        for (std::size_t i = v.shape.size(); i-- > 0;) {
            v.strides[i] = st;
            st *= v.shape[i];
        }
    }
    return v;
}

// ---- Argument checks --------------------------------------------------------------------------------

/// One (N, 3) or (3,) vector argument: pointer, stride (bytes, 0 for (3,)), rows, double or not.
struct Vectors {
    const void* ptr = nullptr;
    std::size_t stride = 0;
    std::size_t rows = 0;  ///< 0 for a (3,) argument (broadcast)
    bool broadcast = false;
    bool f64 = false;
    py::object keep;  ///< the array read (kept alive)
};

Vectors host_vectors(const py::handle& o, const char* name) {
    py::array a = py::array::ensure(o);
    if (!a) throw py::type_error(std::string(name) + ": expected an array of shape (N, 3) or (3,)");
    if (!py::isinstance<py::array_t<float>>(a) && !py::isinstance<py::array_t<double>>(a)) {
        if (a.dtype().kind() != 'f' && a.dtype().kind() != 'i' && a.dtype().kind() != 'u')
            throw py::type_error(std::string(name) + ": expected float32 or float64 values, got dtype " +
                                 std::string(py::str(a.dtype())));
        a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
    }
    Vectors v;
    v.f64 = py::isinstance<py::array_t<double>>(a);
    const std::size_t item = v.f64 ? 8 : 4;
    if (a.ndim() == 1 && a.shape(0) == 3) {
        v.broadcast = true;
    } else if (a.ndim() == 2 && a.shape(1) == 3) {
        v.rows = static_cast<std::size_t>(a.shape(0));
    } else {
        std::string shape = "(";
        for (py::ssize_t i = 0; i < a.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(a.shape(i));
        throw py::value_error(std::string(name) + ": expected shape (N, 3) or (3,), got " + shape + ")");
    }
    // Rows may be strided; the three values of a row must be contiguous.
    if (a.strides(a.ndim() - 1) != static_cast<py::ssize_t>(item) || (a.ndim() == 2 && a.strides(0) < 0))
        a = py::array::ensure(a, py::array::c_style);
    v.ptr = a.data();
    v.stride = v.broadcast ? 0 : static_cast<std::size_t>(a.strides(0));
    v.keep = a;
    return v;
}

Vectors device_vectors(const py::handle& o, const char* name) {
    const DeviceView d = device_view(o, name);
    Vectors v;
    if (d.typestr != "<f4" && d.typestr != "<f8")
        throw py::type_error(std::string(name) + ": expected float32 or float64 device values, got typestr " +
                             d.typestr);
    v.f64 = d.typestr == "<f8";
    const std::size_t item = v.f64 ? 8 : 4;
    if (d.shape.size() == 1 && d.shape[0] == 3) {
        v.broadcast = true;
    } else if (d.shape.size() == 2 && d.shape[1] == 3) {
        v.rows = d.shape[0];
    } else {
        throw py::value_error(std::string(name) + ": expected shape (N, 3) or (3,)");
    }
    if (d.strides.back() != item)
        throw py::value_error(std::string(name) + ": the three values of a row must be contiguous");
    v.ptr = d.ptr;
    v.stride = v.broadcast ? 0 : d.strides[0];
    v.keep = py::reinterpret_borrow<py::object>(o);
    return v;
}

/// t_min / t_max: a number, or a float32 (N,) array (host or device).
struct Range {
    const float* ptr = nullptr;
    std::size_t stride = 4;
    float value = 0.0f;
    py::object keep;
};

Range range_arg(const py::handle& o, const char* name, std::size_t n, bool device) {
    Range r;
    if (py::isinstance<py::float_>(o) || py::isinstance<py::int_>(o)) {
        r.value = static_cast<float>(o.cast<double>());
        return r;
    }
    if (device && has_cuda_interface(o)) {
        const DeviceView d = device_view(o, name);
        if (d.typestr != "<f4") throw py::type_error(std::string(name) + ": expected float32 device values");
        if (d.shape.size() != 1 || d.shape[0] != n)
            throw py::value_error(std::string(name) + ": expected shape (" + std::to_string(n) + ",)");
        r.ptr = static_cast<const float*>(d.ptr);
        r.stride = d.strides[0];
        r.keep = py::reinterpret_borrow<py::object>(o);
        return r;
    }
    if (device) throw py::type_error(std::string(name) + ": a number or a device array with the device rays");
    py::array a = py::array::ensure(o);
    if (!a) throw py::type_error(std::string(name) + ": expected a number or an array of shape (N,)");
    if (a.ndim() == 0) {
        r.value = a.cast<float>();
        return r;
    }
    if (a.dtype().kind() != 'f' && a.dtype().kind() != 'i' && a.dtype().kind() != 'u')
        throw py::type_error(std::string(name) + ": expected numbers, got dtype " +
                             std::string(py::str(a.dtype())));
    py::array_t<float, py::array::c_style | py::array::forcecast> f(a);
    if (f.ndim() != 1 || static_cast<std::size_t>(f.shape(0)) != n)
        throw py::value_error(std::string(name) + ": expected a number or shape (" + std::to_string(n) +
                              ",)");
    r.ptr = f.data();
    r.keep = f;
    return r;
}

/// The rays of a call (host or device), checked.
struct Batch {
    pointrt::RayArrays rays;
    Vectors o, d;
    Range t0, t1;
    bool device = false;
};

Batch make_batch(const py::handle& origins, const py::handle& directions, const py::handle& t_min,
                 const py::handle& t_max) {
    Batch b;
    const bool od = has_cuda_interface(origins), dd = has_cuda_interface(directions);
    if (od != dd)
        throw py::type_error(
            "origins, directions: both host arrays or both device arrays "
            "(__cuda_array_interface__), not one of each");
    b.device = od;
    b.o = b.device ? device_vectors(origins, "origins") : host_vectors(origins, "origins");
    b.d = b.device ? device_vectors(directions, "directions") : host_vectors(directions, "directions");
    std::size_t n = 0;
    if (!b.o.broadcast && !b.d.broadcast && b.o.rows != b.d.rows)
        throw py::value_error("origins, directions: " + std::to_string(b.o.rows) + " and " +
                              std::to_string(b.d.rows) + " rows: expected the same count");
    n = b.o.broadcast ? (b.d.broadcast ? 1 : b.d.rows) : b.o.rows;
    b.t0 = range_arg(t_min, "t_min", n, b.device);
    b.t1 = range_arg(t_max, "t_max", n, b.device);
    pointrt::RayArrays& r = b.rays;
    r.count = n;
    r.origins = b.o.ptr;
    r.directions = b.d.ptr;
    r.origins_f64 = b.o.f64;
    r.directions_f64 = b.d.f64;
    r.origin_stride = b.o.stride;
    r.direction_stride = b.d.stride;
    r.t_min = b.t0.ptr;
    r.t_max = b.t1.ptr;
    r.t_min_stride = b.t0.stride;
    r.t_max_stride = b.t1.stride;
    r.t_min_value = b.t0.value;
    r.t_max_value = b.t1.ptr ? std::numeric_limits<float>::infinity() : b.t1.value;
    r.memory = b.device ? pointrt::Memory::device : pointrt::Memory::host;
    return b;
}

// ---- Outputs ----------------------------------------------------------------------------------------

/// One output field: name, numpy dtype / typestr, item size, values per ray.
struct Field {
    const char* name;
    const char* typestr;
    std::size_t itemsize;
    std::size_t width;
};
constexpr Field k_fields[] = {
    {"hit", "|b1", 1, 1},    {"valid", "|b1", 1, 1}, {"t", "<f4", 4, 1},     {"position", "<f4", 4, 3},
    {"normal", "<f4", 4, 3}, {"color", "<f4", 4, 3}, {"model", "<i4", 4, 1}, {"element", "<i8", 8, 1},
};

void* field_pointer(pointrt::HitArrays& h, std::size_t i) {
    void** slots[] = {reinterpret_cast<void**>(&h.hit),    reinterpret_cast<void**>(&h.valid),
                      reinterpret_cast<void**>(&h.t),      reinterpret_cast<void**>(&h.position),
                      reinterpret_cast<void**>(&h.normal), reinterpret_cast<void**>(&h.color),
                      reinterpret_cast<void**>(&h.model),  reinterpret_cast<void**>(&h.element)};
    return slots[i];
}

void set_field(pointrt::HitArrays& h, std::size_t i, void* p) {
    *static_cast<void**>(field_pointer(h, i)) = p;
}

std::vector<std::size_t> field_shape(const Field& f, std::size_t n) {
    return f.width == 1 ? std::vector<std::size_t>{n} : std::vector<std::size_t>{n, f.width};
}

/// A caller's output array for field f (host numpy or device), checked: dtype, shape, contiguous.
void* out_pointer(const py::handle& o, const Field& f, std::size_t n, bool device) {
    const std::string name = std::string("out['") + f.name + "']";
    const std::vector<std::size_t> shape = field_shape(f, n);
    if (device) {
        if (!has_cuda_interface(o)) throw py::type_error(name + ": expected a device array (device rays)");
        const DeviceView d = device_view(o, name.c_str());
        const std::string want = f.typestr;
        const bool same_type =
            d.typestr == want || (want == "|b1" && (d.typestr == "|u1" || d.typestr == "|i1"));
        if (!same_type) throw py::type_error(name + ": expected typestr " + want + ", got " + d.typestr);
        if (d.shape != shape) throw py::value_error(name + ": wrong shape");
        std::size_t st = f.itemsize;
        for (std::size_t i = d.shape.size(); i-- > 0;) {
            if (d.shape[i] > 1 && d.strides[i] != st) throw py::value_error(name + ": must be contiguous");
            st *= d.shape[i];
        }
        if (d.readonly) throw py::value_error(name + ": is read-only");
        return d.ptr;
    }
    if (has_cuda_interface(o)) throw py::type_error(name + ": expected a numpy array (host rays)");
    py::array a = py::reinterpret_borrow<py::array>(o);
    if (!py::isinstance<py::array>(o)) throw py::type_error(name + ": expected a numpy array");
    if (a.dtype().itemsize() != static_cast<py::ssize_t>(f.itemsize) ||
        (std::string(f.typestr) == "|b1" ? (a.dtype().kind() != 'b' && a.dtype().kind() != 'u')
                                         : py::dtype(f.typestr).not_equal(a.dtype())))
        throw py::type_error(name + ": expected dtype " + std::string(py::str(py::dtype(f.typestr))));
    if (a.ndim() != static_cast<py::ssize_t>(shape.size())) throw py::value_error(name + ": wrong shape");
    for (std::size_t i = 0; i < shape.size(); ++i)
        if (static_cast<std::size_t>(a.shape(i)) != shape[i]) throw py::value_error(name + ": wrong shape");
    if (!(a.flags() & py::array::c_style)) throw py::value_error(name + ": must be C-contiguous");
    if (!a.writeable()) throw py::value_error(name + ": is read-only");
    return a.mutable_data();
}

/// Allocates or takes the outputs of `fields`; returns the dict cast() hands back.
py::dict make_outputs(pointrt::HitArrays& h, std::size_t n, bool device, const py::object& out,
                      const std::vector<std::string>& fields) {
    py::dict result;
    h.memory = device ? pointrt::Memory::device : pointrt::Memory::host;
    for (std::size_t i = 0; i < std::size(k_fields); ++i) {
        const Field& f = k_fields[i];
        bool wanted = false;
        for (const std::string& s : fields) wanted = wanted || s == f.name;
        if (!wanted) continue;
        if (!out.is_none() && py::dict(out).contains(f.name)) {
            py::object o = py::dict(out)[f.name];
            set_field(h, i, out_pointer(o, f, n, device));
            result[f.name] = o;
        } else if (device) {
            auto a = std::make_shared<DeviceArray>(field_shape(f, n), f.typestr, f.itemsize);
            set_field(h, i, a->data());
            result[f.name] = py::cast(a);
        } else {
            const std::vector<std::size_t> s = field_shape(f, n);
            py::array a(py::dtype(f.typestr), std::vector<py::ssize_t>(s.begin(), s.end()));
            set_field(h, i, a.mutable_data());
            result[f.name] = a;
        }
    }
    return result;
}

const std::vector<std::string> k_all_fields = {"hit",    "valid", "t",     "position",
                                               "normal", "color", "model", "element"};

// ---- The scene --------------------------------------------------------------------------------------

class PyScene {
public:
    PyScene(const std::string& path, const std::string& backend, const std::string& surface, unsigned threads)
        : m_scene(pointrt::Scene::open(path, pointrt::Options{backend, surface, threads})) {}

    py::dict cast(const py::object& origins, const py::object& directions, const py::object& t_min,
                  const py::object& t_max, const py::object& out,
                  const std::optional<std::vector<std::string>>& fields) {
        const std::vector<std::string>& f = fields ? *fields : k_all_fields;
        for (const std::string& name : f) {
            bool known = false;
            for (const Field& k : k_fields) known = known || name == k.name;
            if (!known)
                throw py::value_error("fields: unknown field '" + name +
                                      "' (hit, valid, t, position, normal, color, model, element)");
        }
        if (!out.is_none() && !py::isinstance<py::dict>(out))
            throw py::type_error("out: expected a dict of arrays by field name");
        Batch b = make_batch(origins, directions, t_min, t_max);
        pointrt::HitArrays h;
        py::dict result = make_outputs(h, b.rays.count, b.device, out, f);
        pointrt::CastStats st;
        {
            py::gil_scoped_release release;
            st = m_scene.cast(b.rays, h);
        }
        m_last = st;
        return result;
    }

    py::object occluded(const py::object& origins, const py::object& directions, const py::object& t_min,
                        const py::object& t_max, const py::object& out) {
        Batch b = make_batch(origins, directions, t_min, t_max);
        const std::size_t n = b.rays.count;
        const Field& f = k_fields[0];
        py::object result;
        void* flags = nullptr;
        if (!out.is_none()) {
            flags = out_pointer(out, f, n, b.device);
            result = out;
        } else if (b.device) {
            auto a = std::make_shared<DeviceArray>(field_shape(f, n), f.typestr, f.itemsize);
            flags = a->data();
            result = py::cast(a);
        } else {
            py::array a(py::dtype("bool"), std::vector<py::ssize_t>{static_cast<py::ssize_t>(n)});
            flags = a.mutable_data();
            result = a;
        }
        pointrt::CastStats st;
        {
            py::gil_scoped_release release;
            st = m_scene.occluded(b.rays, static_cast<std::uint8_t*>(flags), nullptr);
        }
        m_last = st;
        return result;
    }

    py::array render(const std::optional<std::array<double, 3>>& eye,
                     const std::optional<std::array<double, 3>>& look_at,
                     const std::optional<std::array<double, 3>>& up, std::optional<double> fov,
                     std::uint32_t width, std::uint32_t height) {
        pointrt::Camera cam = m_scene.default_camera(width, height);
        if (eye) cam.eye = *eye;
        if (look_at) cam.look_at = *look_at;
        if (up) cam.up = *up;
        if (fov) cam.fov_y_degrees = *fov;
        pointrt::Image img;
        {
            py::gil_scoped_release release;
            img = m_scene.render(cam, width, height);
        }
        py::array_t<std::uint8_t> a(
            {static_cast<py::ssize_t>(height), static_cast<py::ssize_t>(width), py::ssize_t{4}});
        std::memcpy(a.mutable_data(), img.rgba.data(), img.rgba.size());
        return a;
    }

    py::dict info() const {
        const pointrt::SceneInfo& i = m_scene.info();
        py::dict d;
        d["backend"] = i.backend;
        d["device"] = i.device;
        d["surfaces"] = i.surfaces;
        d["world_min"] = i.world_min;
        d["world_max"] = i.world_max;
        d["points"] = i.points;
        return d;
    }
    py::dict default_camera(std::uint32_t w, std::uint32_t h) const {
        const pointrt::Camera c = m_scene.default_camera(w, h);
        py::dict d;
        d["eye"] = c.eye;
        d["look_at"] = c.look_at;
        d["up"] = c.up;
        d["fov"] = c.fov_y_degrees;
        return d;
    }
    py::dict last_stats() const {
        py::dict d;
        d["seconds"] = m_last.seconds;
        d["device_ms"] = m_last.device_ms;
        d["rays"] = m_last.rays;
        return d;
    }
    std::string backend() const { return m_scene.info().backend; }

private:
    pointrt::Scene m_scene;
    pointrt::CastStats m_last;
};

}  // namespace

PYBIND11_MODULE(pointrt, m) {
    m.doc() = "PointRT: ray casting and rendering of point clouds (pools and scene files) on the CPU and GPU";
    py::register_exception<pointrt::Error>(m, "Error", PyExc_RuntimeError);
    m.attr("__version__") = pointrt::version();

    py::class_<DeviceArray, std::shared_ptr<DeviceArray>>(
        m, "DeviceArray", "GPU memory the library allocated (outputs of device rays)")
        .def_property_readonly("__cuda_array_interface__", &DeviceArray::interface)
        .def_property_readonly("shape", [](const DeviceArray& a) { return py::tuple(py::cast(a.shape())); })
        .def("numpy", &DeviceArray::numpy, "A host copy as a numpy array");

    py::class_<PyScene>(m, "Scene", "An open pool or scene file, uploaded to its backend")
        .def(py::init<const std::string&, const std::string&, const std::string&, unsigned>(),
             py::arg("path"), py::arg("backend") = "auto", py::arg("surface") = "", py::arg("threads") = 0u)
        .def(
            "cast", &PyScene::cast, py::arg("origins"), py::arg("directions"), py::arg("t_min") = 0.0,
            py::arg("t_max") = std::numeric_limits<double>::infinity(), py::arg("out") = py::none(),
            py::arg("fields") = py::none(),
            "Closest hits of rays origin + t * direction, t in [t_min, t_max) (t in units of the direction's "
            "length). origins, directions: (N, 3) or (3,) float32/float64, numpy or (CUDA backend) "
            "__cuda_array_interface__ objects. Returns a dict: hit (bool), valid (bool), t (float32, inf for "
            "misses), position, normal, color ((N, 3) float32, world frame), model (int32, -1), element "
            "(int64: source point, patch, or -1). fields= limits the outputs; out= gives arrays to write "
            "into.")
        .def("occluded", &PyScene::occluded, py::arg("origins"), py::arg("directions"),
             py::arg("t_min") = 0.0, py::arg("t_max") = std::numeric_limits<double>::infinity(),
             py::arg("out") = py::none(),
             "Whether anything lies on [t_min, t_max) of each ray: a bool array (invalid rays: False).")
        .def("render", &PyScene::render, py::arg("eye") = py::none(), py::arg("look_at") = py::none(),
             py::arg("up") = py::none(), py::arg("fov") = py::none(), py::arg("width") = 512u,
             py::arg("height") = 512u,
             "Renders an image (H x W x 4 uint8, row 0 at the top) from eye toward look_at; omitted camera "
             "values come from the default view.")
        .def("default_camera", &PyScene::default_camera, py::arg("width") = 512u, py::arg("height") = 512u)
        .def_property_readonly("info", &PyScene::info)
        .def_property_readonly("backend", &PyScene::backend)
        .def_property_readonly("last_stats", &PyScene::last_stats, "Timing of the last cast/occluded call");

    m.def(
        "open",
        [](const std::string& path, const std::string& backend, const std::string& surface,
           unsigned threads) { return std::make_unique<PyScene>(path, backend, surface, threads); },
        py::arg("path"), py::arg("backend") = "auto", py::arg("surface") = "", py::arg("threads") = 0u,
        "Opens a pool (*.pool) or a scene file (*.json) on a backend: cpu, cuda, hybrid or auto.");
    m.def(
        "render",
        [](const std::string& path, const std::optional<std::array<double, 3>>& eye,
           const std::optional<std::array<double, 3>>& look_at,
           const std::optional<std::array<double, 3>>& up, std::optional<double> fov, std::uint32_t width,
           std::uint32_t height, const std::string& backend) {
            PyScene s(path, backend, "", 0);
            return s.render(eye, look_at, up, fov, width, height);
        },
        py::arg("path"), py::arg("eye") = py::none(), py::arg("look_at") = py::none(),
        py::arg("up") = py::none(), py::arg("fov") = py::none(), py::arg("width") = 512u,
        py::arg("height") = 512u, py::arg("backend") = "auto",
        "Opens a pool or scene file and renders one image (H x W x 4 uint8).");
    m.def("available_backends", &pointrt::available_backends);
}

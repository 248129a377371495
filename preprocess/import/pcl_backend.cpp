// The one translation unit that includes PCL (its headers are heavy): PCD reading and PCA normals.
#include "pcl_backend.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include "prt/mapped_file.h"
#include "pcd_header.h"
#include "progress.h"
#include "prt/error.h"

namespace prt::pre::import {

namespace {

/// PCL prints its own errors on stderr; we report one line of our own instead.
void silence_pcl() {
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
}

/// The `T` stored at `p` (unaligned), as a double.
template <class T>
double load_as_double(const std::uint8_t* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return static_cast<double>(v);
}

/// The field of PCL type `datatype` at `p` as a double; NaN for a type we do not read.
double load_field(const std::uint8_t* p, std::uint8_t datatype) {
    using F = pcl::PCLPointField;
    static constexpr struct {
        std::uint8_t datatype;
        double (*load)(const std::uint8_t*);
    } k_loaders[] = {
        {F::INT8, load_as_double<std::int8_t>},   {F::UINT8, load_as_double<std::uint8_t>},
        {F::INT16, load_as_double<std::int16_t>}, {F::UINT16, load_as_double<std::uint16_t>},
        {F::INT32, load_as_double<std::int32_t>}, {F::UINT32, load_as_double<std::uint32_t>},
        {F::INT64, load_as_double<std::int64_t>}, {F::UINT64, load_as_double<std::uint64_t>},
        {F::FLOAT32, load_as_double<float>},      {F::FLOAT64, load_as_double<double>},
    };
    for (const auto& l : k_loaders)
        if (l.datatype == datatype) return l.load(p);
    return std::numeric_limits<double>::quiet_NaN();
}

std::size_t field_size(std::uint8_t datatype) {
    switch (datatype) {
        case pcl::PCLPointField::INT8:
        case pcl::PCLPointField::UINT8:
            return 1;
        case pcl::PCLPointField::INT16:
        case pcl::PCLPointField::UINT16:
            return 2;
        case pcl::PCLPointField::INT32:
        case pcl::PCLPointField::UINT32:
        case pcl::PCLPointField::FLOAT32:
            return 4;
        case pcl::PCLPointField::INT64:
        case pcl::PCLPointField::UINT64:
        case pcl::PCLPointField::FLOAT64:
            return 8;
        default:
            return 0;
    }
}

}  // namespace

bool have_pcl() {
    return true;
}

PointCloud read_pcd(const std::filesystem::path& path, Report& report, bool quiet) {
    silence_pcl();
    const std::string label = path.string();
    // Our own header and size check first: PCL trusts headers and can crash on garbage.
    const PcdHeader checked = [&] {
        const MappedFile file = MappedFile::open(path);
        return check_pcd(file, report);
    }();

    pcl::PCDReader reader;
    pcl::PCLPointCloud2 blob;
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    int version = 0;
    int data_type = 0;
    unsigned int data_index = 0;
    int rc = -1;
    try {
        rc = reader.readHeader(label, blob, origin, orientation, version, data_type, data_index);
    } catch (const std::exception& e) {
        throw Error(label + ": not a valid PCD file (" + e.what() + ")");
    }
    if (rc < 0) throw Error(label + ": not a valid PCD file (PCL could not parse the header)");
    const std::uint64_t declared = static_cast<std::uint64_t>(blob.width) * blob.height;
    LazyProgress progress("reading " + label, 1, quiet);
    try {
        rc = reader.read(label, blob, origin, orientation, version);
    } catch (const std::exception& e) {
        throw Error(label + ": PCD data unreadable (" + e.what() + ")");
    }
    if (rc < 0)
        throw Error(label + ": PCD data unreadable: truncated or corrupt, or the header's " +
                    std::to_string(declared) + " points (WIDTH x HEIGHT) disagree with the data");
    progress.finish();

    const std::uint64_t n = static_cast<std::uint64_t>(blob.width) * blob.height;
    if (n != checked.points)
        throw Error(label + ": PCL read " + std::to_string(n) + " points but the header declares " +
                    std::to_string(checked.points));
    if (blob.data.size() < n * blob.point_step)
        throw Error(label + ": PCD data holds " +
                    std::to_string(blob.point_step ? blob.data.size() / blob.point_step : 0) +
                    " points but the header declares " + std::to_string(n));
    const pcl::PCLPointField* fx = nullptr;
    const pcl::PCLPointField* fy = nullptr;
    const pcl::PCLPointField* fz = nullptr;
    const pcl::PCLPointField* fn[3] = {nullptr, nullptr, nullptr};
    const pcl::PCLPointField* frgb = nullptr;
    const pcl::PCLPointField* fintensity = nullptr;
    bool rgba = false;
    std::string skipped;
    for (const pcl::PCLPointField& f : blob.fields) {
        const std::size_t fs = field_size(f.datatype);
        if (fs == 0 || f.offset + fs > blob.point_step) {
            skipped += (skipped.empty() ? "" : ", ") + f.name;
            continue;
        }
        if (f.name == "x")
            fx = &f;
        else if (f.name == "y")
            fy = &f;
        else if (f.name == "z")
            fz = &f;
        else if (f.name == "normal_x")
            fn[0] = &f;
        else if (f.name == "normal_y")
            fn[1] = &f;
        else if (f.name == "normal_z")
            fn[2] = &f;
        else if ((f.name == "rgb" || f.name == "rgba") && fs == 4 && !frgb) {
            frgb = &f;
            rgba = f.name == "rgba";
        } else if (f.name == "intensity" && !fintensity) {
            fintensity = &f;
        } else if (f.name != "_") {  // "_" is PCL's padding
            skipped += (skipped.empty() ? "" : ", ") + f.name;
        }
    }
    if (!fx || !fy || !fz) throw Error(label + ": PCD file has no x, y and z fields");
    const bool normals = fn[0] && fn[1] && fn[2];
    if (!normals && (fn[0] || fn[1] || fn[2]))
        report.notes.push_back(label +
                               ": normals incomplete (needs normal_x, normal_y and normal_z): ignored");
    if (!skipped.empty()) report.notes.push_back(label + ": skipped PCD fields: " + skipped);

    PointCloud cloud;
    cloud.positions.reserve(n);
    if (normals) cloud.normals.reserve(n);
    if (frgb) cloud.colors.reserve(n);
    if (fintensity) cloud.intensities.reserve(n);
    for (std::uint64_t i = 0; i < n; ++i) {
        const std::uint8_t* row = blob.data.data() + i * blob.point_step;
        const double x = load_field(row + fx->offset, fx->datatype);
        const double y = load_field(row + fy->offset, fy->datatype);
        const double z = load_field(row + fz->offset, fz->datatype);
        if (std::isnan(x) || std::isnan(y) || std::isnan(z)) {
            ++report.nan_entries;  // an organized cloud's hole: no measurement there
            continue;
        }
        cloud.positions.push_back({x, y, z});
        if (normals)
            cloud.normals.push_back({static_cast<float>(load_field(row + fn[0]->offset, fn[0]->datatype)),
                                     static_cast<float>(load_field(row + fn[1]->offset, fn[1]->datatype)),
                                     static_cast<float>(load_field(row + fn[2]->offset, fn[2]->datatype))});
        if (frgb) {
            // PCL packs colors as 0xAARRGGBB in the bytes of a float or uint32.
            std::uint32_t packed;
            std::memcpy(&packed, row + frgb->offset, 4);
            cloud.colors.push_back({static_cast<std::uint8_t>((packed >> 16) & 0xFF),
                                    static_cast<std::uint8_t>((packed >> 8) & 0xFF),
                                    static_cast<std::uint8_t>(packed & 0xFF),
                                    rgba ? static_cast<std::uint8_t>(packed >> 24) : std::uint8_t{255}});
        }
        if (fintensity)
            cloud.intensities.push_back(
                static_cast<float>(load_field(row + fintensity->offset, fintensity->datatype)));
    }
    if (checked.viewpoint) {
        // PCL: sensor_origin_ = (tx, ty, tz), the sensor's position in the cloud's frame.
        const auto& v = *checked.viewpoint;
        cloud.sensors.push_back(pool::Sensor{{v[0], v[1], v[2]}, pool::k_sensor_point, 0});
        report.sensor_source = "the PCD VIEWPOINT";
    }
    const char* encodings[] = {"ascii", "binary", "binary_compressed"};
    report.reader =
        std::string("pcd (PCL, ") + (data_type >= 0 && data_type <= 2 ? encodings[data_type] : "?") +
        (blob.height > 1 ? ", organized " + std::to_string(blob.width) + "x" + std::to_string(blob.height)
                         : "") +
        ")";
    report.records = n;
    return cloud;
}

}  // namespace prt::pre::import

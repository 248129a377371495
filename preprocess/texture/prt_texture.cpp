// prt-texture: tri-planar texture projection onto point colors (thesis 5.5, eq. 5.5).
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "prt/pool_step.h"
#include "prt/runtime/image.h"
#include "texture_bake.h"

namespace {

namespace fs = std::filesystem;
using namespace prt;

/// Reads an image as linear RGB (8/16-bit files are sRGB-decoded, float files kept linear).
rt::FloatImage read_texture(const std::string& path) {
    if (!fs::is_regular_file(path)) throw Error(path + ": no such image file");
    rt::FloatImage img = rt::read_float_image(path);
    if (img.width == 0 || img.height == 0) throw Error(path + ": empty image");
    return img;
}

std::string absolute_string(const std::string& path) {
    return fs::absolute(path).lexically_normal().string();
}

constexpr const char* k_description =
    "Tri-planar texture (thesis 5.5, eq. 5.5): three axis-aligned planes each carry a tiled copy of "
    "an image; every point of POOL is projected onto the three planes, samples the image there "
    "(bilinear, wrapping) and gets the average of the three samples weighted by |n . n_a|^K (n the "
    "point's normal, n_a the plane's; K = --sharpness, 1 in the thesis). The result is written as "
    "the pool's per-point colors (sRGB 8-bit), which the renderer multiplies by the material's "
    "diffuse color and the light (material use_point_colors), so the light modulates the texture. "
    "Planes: x (u = -z, v = +y), y (u = +x, v = -z), z (u = +x, v = +y), all starting at the "
    "corner of the model's bounding box; v runs towards the image's top. 8/16-bit images are "
    "decoded from sRGB, float images (EXR, HDR, PFM) are used as linear. The other sections are "
    "carried over; ISO sections (their leaves store colors) are dropped: rerun prt-iso.";

/// The options of prt-texture.
struct Options {
    std::string image_x, image_y, image_z, blend_name = "replace";
    double scale = 0.0, sharpness = 1.0;
    unsigned threads = 0;
};

/// The projection planes of the model's bounding box (origin, scale) for the options.
pre::texture::TriplanarParams plane_params(const std::string& input, const pool::ModelInfo& info,
                                           const Options& o) {
    pre::texture::TriplanarParams params;
    double diagonal = 0.0;
    for (int a = 0; a < 3; ++a) {
        params.origin[a] = info.origin[a] + double(info.bounds_min[a]);
        const double e = double(info.bounds_max[a]) - double(info.bounds_min[a]);
        diagonal += e * e;
    }
    diagonal = std::sqrt(diagonal);
    params.scale = o.scale == 0.0 ? diagonal / 4.0 : o.scale;
    if (!(params.scale > 0.0))
        throw Error(input + ": the model's bounding box is a single point; give --scale");
    params.sharpness = o.sharpness;
    return params;
}

void texture_step(tool::PoolStep& step, Options o) {
    step.check_output_folder();
    const pool::PoolFile& in = step.input();
    const auto positions = in.require<pool::Float3>(pool::SectionType::positions, "prt-texture");
    const auto normals = in.require<pool::Float3>(pool::SectionType::normals, "prt-texture");
    const auto old_colors = in.array<pool::Rgba8>(pool::SectionType::colors);
    if (positions.empty()) throw Error(step.input_path() + ": the pool has no points to texture");

    // Every image is read before anything is written: a bad one leaves the pool untouched.
    if (o.image_y.empty()) o.image_y = o.image_x;
    if (o.image_z.empty()) o.image_z = o.image_x;
    const rt::FloatImage img_x = read_texture(o.image_x);
    const rt::FloatImage img_y = o.image_y == o.image_x ? rt::FloatImage{} : read_texture(o.image_y);
    const rt::FloatImage img_z = o.image_z == o.image_x ? rt::FloatImage{} : read_texture(o.image_z);
    auto view_of = [&](const rt::FloatImage& img) {
        const rt::FloatImage& i = img.width > 0 ? img : img_x;
        return pre::texture::TextureView{i.rgb.data(), i.width, i.height};
    };
    const pre::texture::TextureView textures[3] = {view_of(img_x), view_of(img_y), view_of(img_z)};

    const pool::ModelInfo& info = in.model_info();
    const pre::texture::TriplanarParams params = plane_params(step.input_path(), info, o);
    const bool auto_scale = o.scale == 0.0;
    const auto blend =
        o.blend_name == "multiply" ? pre::texture::Blend::multiply : pre::texture::Blend::replace;
    step.note("prt-texture: %zu points, images %ux%u / %ux%u / %ux%u, scale %.6g%s, sharpness %g, blend %s",
              positions.size(), textures[0].width, textures[0].height, textures[1].width, textures[1].height,
              textures[2].width, textures[2].height, params.scale,
              auto_scale ? " (bounding-box diagonal / 4)" : "", o.sharpness, o.blend_name.c_str());

    const double bake_start = tool::now_seconds();
    std::vector<pool::Rgba8> colors = pre::texture::bake_triplanar(
        positions, normals, old_colors, {info.origin[0], info.origin[1], info.origin[2]}, textures, params,
        blend, o.threads);
    const double bake_seconds = tool::now_seconds() - bake_start;

    const bool dropped_iso =
        step.drop_sections({pool::SectionType::iso_info, pool::SectionType::iso_nodes,
                            pool::SectionType::iso_leaves_q8, pool::SectionType::iso_leaves_f32});
    step.writer().add_array(pool::SectionType::colors, std::move(colors));
    const nlohmann::json parameters = {{"image", absolute_string(o.image_x)},
                                       {"image_y", absolute_string(o.image_y)},
                                       {"image_z", absolute_string(o.image_z)},
                                       {"scale", params.scale},
                                       {"scale_auto", auto_scale},
                                       {"sharpness", o.sharpness},
                                       {"blend", o.blend_name},
                                       {"origin", {params.origin[0], params.origin[1], params.origin[2]}}};
    const std::uint64_t bytes = step.write(parameters);
    if (dropped_iso)
        step.note("prt-texture: dropped the input's ISO sections (they store colors: rerun prt-iso)");
    if (blend == pre::texture::Blend::multiply && old_colors.empty())
        step.note("prt-texture: the pool had no colors: multiply acted as replace");
    step.note("prt-texture: time: projection %.3f s, total %.3f s; wrote %s (%llu bytes)", bake_seconds,
              step.seconds(), step.output_path().c_str(), static_cast<unsigned long long>(bytes));
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    tool::PoolStep step(
        "prt-texture", k_description,
        {.input = "Pool file with positions and normals", .input_name = "pool", .output = "", .stats = ""});
    return step.run(
        argc, argv,
        [&](CLI::App& app) {
            app.add_option(
                   "--image", o.image_x,
                   "Texture image (PNG, JPEG, EXR, HDR, PFM, ...): used on every plane not given its own "
                   "below")
                ->required();
            app.add_option("--image-y", o.image_y, "Image for the plane facing y (default: --image)");
            app.add_option("--image-z", o.image_z, "Image for the plane facing z (default: --image)");
            app.add_option(
                   "--scale", o.scale,
                   "Model units (the pool's coordinates, before the scene's transform) per image repeat "
                   "(default 0: the model's bounding-box diagonal / 4)")
                ->check(CLI::Range(0.0, 1.0e30));
            app.add_option("--sharpness", o.sharpness,
                           "K: plane weight = |n . n_a|^K (default 1, eq. 5.5; larger narrows the blend)")
                ->check(CLI::Range(0.0, 1000.0));
            app.add_option(
                   "--blend", o.blend_name,
                   "replace (the texture's color, default) or multiply (existing colors x texture, in "
                   "linear RGB)")
                ->check(CLI::IsMember({"replace", "multiply"}));
            step.add_output(app, "Output pool (written atomically; default: rewrite POOL in place)");
            tool::PoolStep::add_threads(app, o.threads, "Worker threads (default 0: every core the process may use)");
        },
        [&](tool::PoolStep& s) { texture_step(s, o); });
}

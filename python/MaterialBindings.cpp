// osgbtf: fitted materials (methods, osgbtf.Material, open_material): evaluated on the CPU by
// Material::evaluate, rendered through the method's shader by harness/MaterialImage.h (headless
// EGL), saved and opened as any front end does (scene/OpenMaterial.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/FloatImage.h"
#include "harness/MaterialImage.h"
#include "harness/headless/HeadlessRenderer.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodOptions.h"
#include "materials/MethodRegistry.h"
#include "python/Bindings.h"
#include "scene/OpenMaterial.h"

namespace osgBTF::python {

namespace {

py::dict materialOptions(const PyMaterial& m) {
    py::dict out;
    for (const auto& [key, value] : m.get().fitInfo)
        if (key.rfind("option.", 0) == 0) out[py::str(key.substr(7))] = value;
    return out;
}

/** A direction from Python: (theta, phi) in degrees, or a 3-vector (unit, pointing away from
 *  the surface). */
glm::vec3 directionFrom(const py::handle& value, const char* what) {
    const std::vector<float> v = value.cast<std::vector<float>>();
    if (v.size() == 2) {
        if (!(v[0] >= 0 && v[0] < 90))
            throw py::value_error(std::string(what) + ": theta " + std::to_string(v[0]) +
                                  " is not in [0, 90)");
        return Direction{v[0], v[1]}.toVector();
    }
    if (v.size() == 3) return glm::vec3(v[0], v[1], v[2]);
    throw py::value_error(std::string(what) +
                          " must be (theta, phi) in degrees or an (x, y, z) vector");
}

/** A FloatImage handed to numpy without a copy: the array owns it through a capsule. */
py::array imageArray(FloatImage&& image) {
    auto* owned = new FloatImage(std::move(image));
    py::capsule owner(owned, [](void* p) { delete static_cast<FloatImage*>(p); });
    return py::array_t<float>(
        {py::ssize_t(owned->height), py::ssize_t(owned->width), py::ssize_t(owned->channels)},
        owned->pixels.data(), owner);
}

/** Rows of an (N, k) array, or one (k,) row for all N. */
struct Rows {
    FloatArray array;
    bool broadcast = false;
    std::size_t count = 0;
    Rows(const py::handle& value, py::ssize_t k, const char* what)
        : array(FloatArray::ensure(value)) {
        if (!array) throw py::value_error(std::string(what) + " must be an array of numbers");
        if (array.ndim() == 1 && array.shape(0) == k) {
            broadcast = true;
        } else if (array.ndim() == 2 && array.shape(1) == k) {
            count = std::size_t(array.shape(0));
        } else {
            throw py::value_error(std::string(what) + " must have shape (N, " + std::to_string(k) +
                                  ") or (" + std::to_string(k) + ",)");
        }
    }
    const float* row(std::size_t i, py::ssize_t k) const {
        return array.data() + (broadcast ? 0 : i * std::size_t(k));
    }
};

/** The texels of the material's images: its size, or its base level's when mip-mapped (its
 *  texels are then an atlas of every level). */
std::pair<int, int> baseSize(const Material& material) {
    if (material.mipLayout().mipMapped())
        return {material.mipLayout().baseWidth(), material.mipLayout().baseHeight()};
    return {material.width(), material.height()};
}

/** Material::evaluate for N queries: texel under uv (nearest, wrapped; v from the bottom as OSG
 *  texture coordinates), or with filter="bilinear" evaluateFiltered at level 0. */
py::array_t<float> evaluate(const PyMaterial& m, const py::handle& uv, const py::handle& views,
                            const py::handle& lights, const std::string& filter) {
    const Material& material = m.get();
    if (filter != "nearest" && filter != "bilinear")
        throw py::value_error("filter must be nearest or bilinear, got '" + filter + "'");
    const Rows u(uv, 2, "uv"), v(views, 3, "view_dirs"), l(lights, 3, "light_dirs");
    std::size_t n = 1;
    bool sized = false;
    for (const Rows* r : {&u, &v, &l}) {
        if (r->broadcast) continue;
        if (sized && r->count != n)
            throw py::value_error(
                "uv, view_dirs and light_dirs must have the same N (or be one row each)");
        n = r->count;
        sized = true;
    }
    py::array_t<float> out({py::ssize_t(n), py::ssize_t(3)});
    float* o = out.mutable_data();
    const bool bilinear = filter == "bilinear";
    const auto [w, h] = baseSize(material);
    {
        py::gil_scoped_release release;
        for (std::size_t i = 0; i < n; ++i) {
            const float* t = u.row(i, 2);
            const float* a = v.row(i, 3);
            const float* b = l.row(i, 3);
            const glm::vec3 view(a[0], a[1], a[2]), light(b[0], b[1], b[2]);
            glm::vec3 value;
            if (!std::isfinite(t[0]) || !std::isfinite(t[1]))
                value = glm::vec3(std::numeric_limits<float>::quiet_NaN());
            else if (bilinear)
                value = material.evaluateFiltered(t[0], t[1], 0.0f, view, light);
            else {
                int x = int(std::floor(double(t[0]) * w)) % w;
                int y = int(std::floor(double(t[1]) * h)) % h;
                if (x < 0) x += w;
                if (y < 0) y += h;
                value = material.evaluate(x, y, view, light);
            }
            o[i * 3] = value.r;
            o[i * 3 + 1] = value.g;
            o[i * 3 + 2] = value.b;
        }
    }
    return out;
}

// ---- headless rendering ------------------------------------------------------------------------

std::mutex g_rendererMutex;
std::unique_ptr<HeadlessRenderer> g_renderer;

HeadlessRenderer& renderer() {
    if (!g_renderer) g_renderer = std::make_unique<HeadlessRenderer>();
    return *g_renderer;
}

/** The patch drawn into a w x h image (not one pixel per texel): the material's StateSet on
 *  harness/MaterialImage.h's rectified patch, texture coordinates 0..1 across the image, so the
 *  texels are filtered (and mip levels picked) by the shader. Rows top-down. */
FloatImage renderPatch(HeadlessRenderer& renderer, const Material& material, int w, int h,
                       const glm::vec3& view, const glm::vec3& light) {
    osg::ref_ptr<osg::StateSet> lighting = new osg::StateSet;
    addRectifiedLighting(*lighting, view, light);
    osg::ref_ptr<osg::Geode> patch = rectifiedPatch();
    patch->setStateSet(lighting.get());
    osg::ref_ptr<osg::Group> root = new osg::Group;
    root->setStateSet(material.createStateSet().get());
    root->addChild(patch.get());
    const osg::ref_ptr<osg::Image> image = renderer.render(root.get(), orthoUnitSquare(w, h));
    return rgbTopDown(*image, w, h);
}

/** Its CPU reference: evaluateFiltered at each pixel centre, at the level of detail the pixel's
 *  footprint gives (log2 of texels per pixel, the larger of the two axes, as GL picks it). */
FloatImage evaluatePatch(const Material& material, int w, int h, const glm::vec3& view,
                         const glm::vec3& light) {
    FloatImage out(w, h, 3);
    out.channelNames = {"R", "G", "B"};
    if (light.z <= 0.0f || view.z <= 0.0f) return out;  // as the shader
    const auto [bw, bh] = baseSize(material);
    const float lod = std::log2(std::max(float(bw) / float(w), float(bh) / float(h)));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec3 value = material.evaluateFiltered(
                (float(x) + 0.5f) / float(w), (float(y) + 0.5f) / float(h), lod, view, light);
            for (int c = 0; c < 3; ++c) out.at(x, h - 1 - y, c) = value[c];
        }
    return out;
}

}  // namespace

void bindMaterials(py::module_& m) {
    // The renderer's GL context goes before the interpreter (and EGL's own exit handlers).
    py::module_::import("atexit").attr("register")(py::cpp_function([] {
        std::lock_guard<std::mutex> lock(g_rendererMutex);
        g_renderer.reset();
    }));

    m.def(
        "methods",
        []() {
            py::list out;
            for (const std::string& name : methodNamesInOrder()) {
                const MethodInfo& method = findMethod(name);
                py::list options;
                for (const OptionSpec& o : method.options) {
                    py::dict option;
                    option["name"] = o.name;
                    option["type"] = o.typeName();
                    option["default"] = o.defaultValue;
                    option["allowed"] = o.allowed();
                    if (o.type == OptionSpec::Type::Int || o.type == OptionSpec::Type::Float) {
                        option["min"] = o.min;
                        option["max"] = o.max == OptionSpec::kNoLimit
                                            ? py::object(py::none())
                                            : py::object(py::float_(o.max));
                    }
                    if (o.type == OptionSpec::Type::Enum) option["choices"] = o.choices;
                    option["doc"] = o.doc;
                    option["help"] = optionHelp(o);
                    options.append(option);
                }
                py::dict entry;
                entry["name"] = method.name;
                entry["description"] = method.description;
                entry["options"] = options;
                entry["baseline"] = method.baseline;
                entry["can_fit"] = bool(method.fit);
                entry["quick_fit_options"] = method.quickFitOptions;
                out.append(entry);
            }
            return out;
        },
        "Every registered method with its option schema (the table `btf fit --help` prints), "
        "in the papers' order: a list of dicts {name, description, options: [{name, type, "
        "default, allowed, min, max, choices, doc, help}], baseline, can_fit, "
        "quick_fit_options}.");

    py::class_<PyMaterial>(m, "Material",
                           "A fitted material: any method's, fitted here or opened from a file.")
        .def_property_readonly("method", [](const PyMaterial& p) { return p.get().methodName(); })
        .def_property_readonly(
            "width", [](const PyMaterial& p) { return baseSize(p.get()).first; },
            "Texels across (of the base level for a mip-mapped material)")
        .def_property_readonly("height",
                               [](const PyMaterial& p) { return baseSize(p.get()).second; })
        .def_property_readonly(
            "options", &materialOptions,
            "The method's options as the fit used them (every option, defaults included), for "
            "materials fitted by this module and files it saved; {} for other files")
        .def_property_readonly(
            "fit_info", [](const PyMaterial& p) { return p.get().fitInfo; },
            "What the fit recorded (time, iterations, energy, ...), as text")
        .def_property_readonly(
            "bytes_per_texel", [](const PyMaterial& p) { return p.get().memory().bytesPerTexel; },
            "Storage per texel as Meseth et al. 2003 Table 2 counts it")
        .def_property_readonly("values_per_texel",
                               [](const PyMaterial& p) { return p.get().memory().valuesPerTexel; })
        .def_property_readonly("total_bytes",
                               [](const PyMaterial& p) { return p.get().memory().totalBytes; })
        .def_property_readonly("mip_levels",
                               [](const PyMaterial& p) { return p.get().mipLayout().levelCount(); })
        .def_property_readonly(
            "views", [](const PyMaterial& p) { return directionVectors(p.get().views()); })
        .def_property_readonly(
            "lights", [](const PyMaterial& p) { return directionVectors(p.get().lights()); })
        .def_property_readonly("source_file",
                               [](const PyMaterial& p) { return p.get().sourceFile; })
        .def("evaluate", &evaluate, py::arg("uv"), py::arg("view_dirs"), py::arg("light_dirs"),
             py::arg("filter") = "nearest",
             "The CPU reference (Material::evaluate, the shader's math) for N queries: uv (N, "
             "2) texture coordinates in [0, 1) (v from the bottom), view_dirs and light_dirs (N, "
             "3) unit vectors in the local frame; any of them may be one row for all. -> (N, 3) "
             "float32. filter='nearest': the texel under uv (wrapped); 'bilinear': the four "
             "texels around uv blended as GL_LINEAR (evaluateFiltered, level 0).")
        .def(
            "image",
            [](const PyMaterial& p, const py::object& view, const py::object& light) {
                const glm::vec3 v = directionFrom(view, "view"), l = directionFrom(light, "light");
                FloatImage image;
                {
                    py::gil_scoped_release release;
                    image = evaluateMaterialImage(p.get(), v, l);
                }
                return imageArray(std::move(image));
            },
            py::arg("view"), py::arg("light"),
            "The CPU image of (view, light): (height, width, 3) float32, one pixel per texel, "
            "rows top-down: what `btf eval --cpu` writes. Directions as (theta, phi) in degrees "
            "or (x, y, z) vectors.")
        .def(
            "render",
            [](const PyMaterial& p, const py::object& view, const py::object& light,
               const py::object& size) {
                const glm::vec3 v = directionFrom(view, "view"), l = directionFrom(light, "light");
                int w = 0, h = 0;
                if (!size.is_none()) {
                    if (py::isinstance<py::int_>(size)) {
                        w = h = size.cast<int>();
                    } else {
                        const auto wh = size.cast<std::pair<int, int>>();
                        w = wh.first;
                        h = wh.second;
                    }
                    if (w < 1 || h < 1 || w > 8192 || h > 8192)
                        throw py::value_error("size must be in 1..8192, got " + std::to_string(w) +
                                              "x" + std::to_string(h));
                }
                FloatImage gpu, cpu;
                {
                    py::gil_scoped_release release;
                    std::lock_guard<std::mutex> lock(g_rendererMutex);
                    if (size.is_none()) {
                        gpu = renderMaterialImage(renderer(), p.get(), v, l);
                        cpu = evaluateMaterialImage(p.get(), v, l);
                    } else {
                        gpu = renderPatch(renderer(), p.get(), w, h, v, l);
                        cpu = evaluatePatch(p.get(), w, h, v, l);
                    }
                }
                const double difference = maxAbsDifference(gpu, cpu);
                return py::make_tuple(imageArray(std::move(gpu)), difference);
            },
            py::arg("view"), py::arg("light"), py::arg("size") = py::none(),
            "The image of (view, light) through the GPU path (the method's shader, headless "
            "OpenGL: EGL, as `btf eval`): returns (image, difference), the (height, width, 3) "
            "float32 image, rows top-down, and its largest difference to the CPU reference. "
            "size None: one pixel per texel, `btf eval`'s image; size N or (w, h): the patch "
            "drawn into that many pixels, the shader filtering the texels (bilinear, mip levels "
            "of a mip-mapped material), against evaluate(filter='bilinear') at the level the "
            "footprint gives.")
        .def(
            "save",
            [](const PyMaterial& p, const std::string& path) {
                py::gil_scoped_release release;
                saveMaterial(p.get(), path);
            },
            py::arg("path"),
            "Saves the fitted-material file (.btfmat or .exr, multi-part OpenEXR), atomically")
        .def("__repr__", [](const PyMaterial& p) {
            std::ostringstream text;
            text << "<osgbtf.Material " << p.get().methodName() << ", " << baseSize(p.get()).first
                 << "x" << baseSize(p.get()).second << ", " << p.get().memory().bytesPerTexel
                 << " bytes per texel>";
            return text.str();
        });

    m.def(
        "open_material",
        [](const std::string& path, const std::string& storage) {
            if (storage != "half" && storage != "float")
                throw py::value_error("storage must be half or float, got '" + storage + "'");
            PyMaterial out;
            py::gil_scoped_release release;
            out.material = openMaterial(
                path, storage == "float" ? MaterialTexture::Float : MaterialTexture::Half);
            return out;
        },
        py::arg("path"), py::arg("storage") = "half",
        "Opens any fitted-material file, or a UBO2014 .btf as the fmf material of its stored "
        "factors (storage: their texture storage, as `btf eval --storage`).");
}

}  // namespace osgBTF::python

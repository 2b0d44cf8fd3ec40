// osgbtf: the Python module, a thin pybind11 layer over the C++ API (python/README.md,
// docs/python.md). Measured BTFs through openBtfSource (a UBO2014 file stays factored), fits
// through the method registry (options checked by validateOptions, progress and cancellation
// through core/Progress's observer), materials evaluated by Material::evaluate and rendered by
// harness/MaterialImage.h, comparisons scored as `btf batch` scores a job. Arrays are written
// by C++ straight into the numpy buffers they are returned in.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <dlfcn.h>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "core/FloatImage.h"
#include "core/MeasuredBtf.h"
#include "core/MipPyramid.h"
#include "core/Progress.h"
#include "fit/MipMapping.h"
#include "harness/Compare.h"
#include "harness/FitRunner.h"
#include "harness/MaterialImage.h"
#include "harness/batch/Holdout.h"
#include "harness/headless/HeadlessRenderer.h"
#include "harness/sample/SampleBtf.h"
#include "harness/sample/Ubo2003Writer.h"
#include "loaders/LoadBtf.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodOptions.h"
#include "materials/MethodRegistry.h"
#include "scene/OpenMaterial.h"

namespace py = pybind11;
using namespace osgBTF;

namespace {

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

// ---- measured BTFs ----------------------------------------------------------------------------

struct PyBtf {
    std::shared_ptr<const BtfSource> source;
    std::string path;  ///< empty for the in-memory sample
};

std::uint64_t memoryLimitFrom(const py::object& limit) {
    if (py::isinstance<py::str>(limit)) return parseBytes(limit.cast<std::string>());
    const long long bytes = limit.cast<long long>();
    if (bytes <= 0)
        throw py::value_error("memory_limit must be positive, got " + std::to_string(bytes));
    return std::uint64_t(bytes);
}

LoadOptions loadOptionsFrom(const std::string& decode, const std::string& storage) {
    LoadOptions options;
    if (decode == "linear")
        options.curve = LoadOptions::DecodeCurve::Linear;
    else if (decode == "srgb")
        options.curve = LoadOptions::DecodeCurve::Srgb;
    else if (decode == "gamma22")
        options.curve = LoadOptions::DecodeCurve::Gamma22;
    else
        throw py::value_error("decode must be one of linear, srgb, gamma22, got '" + decode + "'");
    if (storage == "float")
        options.storage = Storage::Float;
    else if (storage == "half")
        options.storage = Storage::Half;
    else
        throw py::value_error("storage must be float or half, got '" + storage + "'");
    return options;
}

/** (n, 3) unit vectors of a direction set. */
py::array_t<float> directionVectors(const DirectionSet& set) {
    py::array_t<float> out({py::ssize_t(set.size()), py::ssize_t(3)});
    auto a = out.mutable_unchecked<2>();
    for (std::size_t i = 0; i < set.size(); ++i) {
        const glm::vec3 v = set.vector(i);
        for (int c = 0; c < 3; ++c) a(py::ssize_t(i), c) = v[c];
    }
    return out;
}

/** (n, 2) theta, phi in degrees. */
py::array_t<float> directionAngles(const DirectionSet& set) {
    py::array_t<float> out({py::ssize_t(set.size()), py::ssize_t(2)});
    auto a = out.mutable_unchecked<2>();
    for (std::size_t i = 0; i < set.size(); ++i) {
        a(py::ssize_t(i), 0) = set[i].theta;
        a(py::ssize_t(i), 1) = set[i].phi;
    }
    return out;
}

std::size_t checkedIndex(py::ssize_t index, std::size_t count, const char* what) {
    if (index < 0 || std::size_t(index) >= count)
        throw py::index_error(std::string(what) + " index " + std::to_string(index) +
                              " is not in 0.." + std::to_string(count - 1));
    return std::size_t(index);
}

/** One measured image, rows top-down (as image files and `btf eval`), (height, width, 3):
 *  read bottom-up straight into the array's buffer and returned as a row-reversed view of it. */
py::array image(const PyBtf& btf, py::ssize_t view, py::ssize_t light) {
    const BtfSource& s = *btf.source;
    const std::size_t v = checkedIndex(view, s.viewCount(), "view");
    const std::size_t l = checkedIndex(light, s.lightCount(), "light");
    py::array_t<float> out({py::ssize_t(s.height()), py::ssize_t(s.width()), py::ssize_t(3)});
    float* data = out.mutable_data();
    {
        py::gil_scoped_release release;
        s.readImages(v * s.lightCount() + l, 1, data);
    }
    return out[py::slice(py::none(), py::none(), py::int_(-1))];
}

/** The ABRDFs of a block of texels: (h, w, views, lights, 3), [j, i] = texel (x + i, y + j),
 *  y counted from the bottom as in the C++ API. Decoded block by block for a UBO2014 file. */
py::array_t<float> texels(const PyBtf& btf, int x, int y, int w, int h) {
    const BtfSource& s = *btf.source;
    if (w <= 0 || h <= 0 || x < 0 || y < 0 || x + w > s.width() || y + h > s.height())
        throw py::index_error("texels " + std::to_string(w) + "x" + std::to_string(h) + " at (" +
                              std::to_string(x) + ", " + std::to_string(y) +
                              ") are not inside the " + std::to_string(s.width()) + "x" +
                              std::to_string(s.height()) + " BTF");
    const std::size_t perTexel = s.imageCount() * 3;
    checkMemory(std::uint64_t(w) * std::uint64_t(h) * perTexel * sizeof(float),
                "texels " + std::to_string(w) + "x" + std::to_string(h));
    py::array_t<float> out({py::ssize_t(h), py::ssize_t(w), py::ssize_t(s.viewCount()),
                            py::ssize_t(s.lightCount()), py::ssize_t(3)});
    float* data = out.mutable_data();
    py::gil_scoped_release release;
    std::vector<std::size_t> row(static_cast<std::size_t>(w));
    for (int j = 0; j < h; ++j) {
        for (int i = 0; i < w; ++i)
            row[std::size_t(i)] = std::size_t(y + j) * std::size_t(s.width()) + std::size_t(x + i);
        s.readAbrdfs(row.data(), row.size(), data + std::size_t(j) * std::size_t(w) * perTexel);
    }
    return out;
}

// ---- fitting: progress, cancellation, the GIL --------------------------------------------------

std::atomic<bool> g_interrupted{false};
extern "C" void onInterrupt(int) {
    g_interrupted = true;
    Progress::requestStop();
}

/** What a fit's progress observer shares with the calling thread. */
struct FitState {
    py::object callback;  ///< None or callable(label, done, total)
    std::mutex mutex;
    bool callbackStopped = false;
    py::object exception;  ///< what the callback raised (set with the GIL held)
};

/** For one fit (or comparison): the observer that calls the Python callback (from any worker,
 *  taking the GIL) and a SIGINT handler (main thread only) that asks the work to stop, both
 *  installed for each run() only. Runs are one at a time: the observer and the stop are
 *  process-wide. */
class FitScope {
public:
    explicit FitScope(py::object callback) : _state(std::make_shared<FitState>()) {
        _state->callback = std::move(callback);
        py::module_ threading = py::module_::import("threading");
        _mainThread = threading.attr("current_thread")().is(threading.attr("main_thread")());
    }
    /** Runs `work` without the GIL, under the observer; raises what stopped it. */
    template <typename Work>
    auto run(Work&& work) -> decltype(work()) {
        static std::mutex fitMutex;
        std::optional<decltype(work())> result;
        bool stopped = false;
        {
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> lock(fitMutex);
            Progress::clearStop();
            g_interrupted = false;
            struct sigaction previous {};
            if (_mainThread) {
                struct sigaction action {};
                action.sa_handler = onInterrupt;
                sigemptyset(&action.sa_mask);
                sigaction(SIGINT, &action, &previous);
            }
            const std::shared_ptr<FitState> state = _state;
            Progress::setObserver(
                [state](const std::string& label, std::size_t done, std::size_t total) {
                    if (state->callback.is_none()) return true;
                    py::gil_scoped_acquire gil;
                    std::lock_guard<std::mutex> lock(state->mutex);
                    if (state->callbackStopped) return false;
                    try {
                        const py::object answer = state->callback(label, done, total);
                        if (!answer.is_none() && !answer.cast<bool>())
                            state->callbackStopped = true;
                    } catch (py::error_already_set& e) {
                        state->exception = e.value();
                        state->callbackStopped = true;
                    }
                    return !state->callbackStopped;
                });
            std::exception_ptr failure;
            try {
                result.emplace(work());
            } catch (...) {
                failure = std::current_exception();
            }
            // Asked to stop: whatever the work threw on its way out (Progress::Cancelled, or an
            // error a method made of it) is the stop.
            stopped = Progress::stopRequested();
            Progress::setObserver(nullptr);
            if (_mainThread) sigaction(SIGINT, &previous, nullptr);
            Progress::clearStop();
            if (failure && !stopped) std::rethrow_exception(failure);
        }
        if (g_interrupted) {
            // Ctrl-C during the work (also when it finished before noticing).
            PyErr_SetNone(PyExc_KeyboardInterrupt);
            throw py::error_already_set();
        }
        if (stopped) {
            if (_state->exception) {
                PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(_state->exception.ptr())),
                                _state->exception.ptr());
                throw py::error_already_set();
            }
            PyErr_SetString(PyExc_KeyboardInterrupt, "the progress callback stopped the work");
            throw py::error_already_set();
        }
        return std::move(*result);
    }

private:
    std::shared_ptr<FitState> _state;
    bool _mainThread = false;
};

/** Python values as the option text a user would type: True -> 1, 0.25 -> 0.25. */
std::string optionText(const py::handle& value) {
    if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "1" : "0";
    if (py::isinstance<py::float_>(value)) {
        std::ostringstream text;
        text.precision(17);
        text << value.cast<double>();
        return text.str();
    }
    return py::str(value).cast<std::string>();
}

/** The method and its validated options; registry errors become ValueError. */
std::pair<const MethodInfo*, FitOptions> checkedMethod(const std::string& name,
                                                       const py::dict& options) {
    const MethodInfo* method = findMethodIfRegistered(name);
    if (!method) {
        try {
            findMethod(name);  // the registry's message, with the known names
        } catch (const Error& e) {
            throw py::value_error(e.what());
        }
    }
    FitOptions fit;
    for (const auto& [key, value] : options) {
        std::string k = py::str(key).cast<std::string>();
        // Python keywords cannot hold '-': max_exponent=... is option max-exponent.
        if (!findOption(*method, k)) {
            std::string dashed = k;
            for (char& c : dashed)
                if (c == '_') c = '-';
            if (findOption(*method, dashed)) k = dashed;
        }
        fit.set(k, optionText(value));
    }
    try {
        validateOptions(*method, fit);
    } catch (const Error& e) {
        throw py::value_error(e.what());
    }
    return {method, fit};
}

// ---- materials ---------------------------------------------------------------------------------

struct PyMaterial {
    osg::ref_ptr<Material> material;
    const Material& get() const {
        if (!material) throw Error("the material was released");
        return *material;
    }
};

/** Every option of the method with the value the fit used, recorded in fitInfo as option.<name>
 *  (saved with the material, so open_material gives them back). */
void recordOptions(Material& material, const MethodInfo& method, const FitOptions& fit) {
    for (const OptionSpec& option : method.options) {
        const auto given = fit.values().find(option.name);
        material.fitInfo["option." + option.name] =
            given != fit.values().end() ? given->second : option.defaultValue;
    }
}

/** An ErrorSummary as error() and error_of() return it. */
py::dict errorDict(const ErrorSummary& e) {
    py::dict out;
    out["average"] = e.average;
    out["minimum"] = e.minimum;
    out["maximum"] = e.maximum;
    out["rmse"] = e.rmse;
    out["psnr"] = e.psnr;
    out["texels"] = e.texelsCompared;
    out["non_finite"] = e.nonFiniteValues;
    return out;
}

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
    FloatImage out(w, h, 3);
    out.channelNames = {"R", "G", "B"};
    const float* rgba = reinterpret_cast<const float*>(image->data());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                out.at(x, h - 1 - y, c) = rgba[(std::size_t(y) * std::size_t(w) + x) * 4 + c];
    return out;
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

// ---- comparison --------------------------------------------------------------------------------

/** The btf executable for `btf compare`'s child fits: beside the module in the build tree
 *  (build/python -> build/bin/btf), in <prefix>/bin for an installed module, else on PATH. */
std::string findBtfTool() {
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&findBtfTool), &info) && info.dli_fname) {
        namespace fs = std::filesystem;
        const fs::path here = fs::path(info.dli_fname).parent_path();
        for (const fs::path& candidate :
             {here / ".." / "bin" / "btf", here / ".." / ".." / ".." / "bin" / "btf",
              here / ".." / ".." / ".." / ".." / "bin" / "btf"}) {
            std::error_code ec;
            if (fs::is_regular_file(candidate, ec))
                return fs::weakly_canonical(candidate, ec).string();
        }
    }
    return "btf";
}

double numberOrNan(double value) {
    return std::isfinite(value) ? value : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

PYBIND11_MODULE(osgbtf, m) {
    m.doc() =
        "osgBTF from Python: measured BTFs, the compression methods, fitted materials, "
        "comparisons (docs/python.md).";
    static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const Progress::Cancelled& e) {
            PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
        } catch (const Error& e) {
            PyErr_SetString(error.ptr(), e.what());
        }
    });
    // The renderer's GL context goes before the interpreter (and EGL's own exit handlers).
    py::module_::import("atexit").attr("register")(py::cpp_function([] {
        std::lock_guard<std::mutex> lock(g_rendererMutex);
        g_renderer.reset();
    }));

    py::class_<PyBtf>(m, "Btf",
                      "A measured BTF: a UBO2003/ATRIUM zip or folder in memory, or a UBO2014 "
                      ".btf file kept as its factors and decoded block by block on demand.")
        .def_property_readonly("width", [](const PyBtf& b) { return b.source->width(); })
        .def_property_readonly("height", [](const PyBtf& b) { return b.source->height(); })
        .def_property_readonly(
            "views", [](const PyBtf& b) { return directionVectors(b.source->views()); },
            "(n, 3) float32: the measured view directions, unit vectors in the local frame "
            "(+Z normal), in the data's index order")
        .def_property_readonly(
            "lights", [](const PyBtf& b) { return directionVectors(b.source->lights()); },
            "(n, 3) float32: the measured light directions, as views")
        .def_property_readonly(
            "view_angles", [](const PyBtf& b) { return directionAngles(b.source->views()); },
            "(n, 2) float32: theta, phi of the view directions in degrees")
        .def_property_readonly(
            "light_angles", [](const PyBtf& b) { return directionAngles(b.source->lights()); },
            "(n, 2) float32: theta, phi of the light directions in degrees")
        .def_property_readonly("path", [](const PyBtf& b) { return b.path; })
        .def_property_readonly(
            "in_memory", [](const PyBtf& b) { return b.source->inMemory(); },
            "False for a UBO2014 file: every read decodes from its factors")
        .def_property_readonly(
            "decoded_bytes", [](const PyBtf& b) { return b.source->decodedBytes(); },
            "bytes of all values as float32 (what decoding the whole BTF would take)")
        .def("image", &image, py::arg("view"), py::arg("light"),
             "The measured image of (view, light) indices: (height, width, 3) float32, rows "
             "top-down like image files")
        .def("texels", &texels, py::arg("x"), py::arg("y"), py::arg("w"), py::arg("h"),
             "The ABRDFs of a w x h block of texels: (h, w, views, lights, 3) float32, [j, i] "
             "= texel (x + i, y + j) with y counted from the bottom; refused above the memory "
             "limit")
        .def("__repr__", [](const PyBtf& b) {
            return "<osgbtf.Btf " + std::to_string(b.source->width()) + "x" +
                   std::to_string(b.source->height()) + ", " +
                   std::to_string(b.source->viewCount()) + " views x " +
                   std::to_string(b.source->lightCount()) + " lights" +
                   (b.path.empty() ? std::string() : ", " + b.path) + ">";
        });

    m.def(
        "load",
        [](const std::string& path, const py::object& memoryLimit, const std::string& decode,
           const std::string& storage) {
            const LoadOptions options = loadOptionsFrom(decode, storage);
            if (!memoryLimit.is_none()) setMemoryLimit(memoryLimitFrom(memoryLimit));
            std::unique_ptr<BtfSource> source;
            {
                py::gil_scoped_release release;
                source = openBtfSource(path, options);
            }
            return PyBtf{std::shared_ptr<const BtfSource>(std::move(source)), path};
        },
        py::arg("path"), py::arg("memory_limit") = py::none(), py::arg("decode") = "linear",
        py::arg("storage") = "float",
        "Opens a measured BTF (UBO2003/ATRIUM zip or folder, UBO2014 .btf). memory_limit (bytes, "
        "or text like '512M') sets the process-wide limit every allocation of measured data is "
        "checked against, like `btf --memory-limit`. decode: linear, srgb or gamma22 for 8/16-bit "
        "images; storage: float or half.");

    m.def(
        "memory_limit", []() { return memoryLimit(); },
        "The process-wide memory limit in bytes that allocations of measured data are checked "
        "against (3/4 of physical memory unless OSGBTF_MEMORY_LIMIT or load(memory_limit=) set "
        "it).");

    m.def(
        "sample",
        [](int size, float variation, const py::object& path, const std::string& format,
           int quality, int weaveRepeats) -> py::object {
            if (size < 4 || size > 4096)
                throw py::value_error("size must be in 4..4096, got " + std::to_string(size));
            if (!(variation >= 0 && variation <= 1))
                throw py::value_error("variation must be in 0..1, got " +
                                      std::to_string(variation));
            Ubo2003ImageFormat imageFormat;
            if (format == "jpg")
                imageFormat = Ubo2003ImageFormat::Jpeg;
            else if (format == "png")
                imageFormat = Ubo2003ImageFormat::Png;
            else if (format == "hdr")
                imageFormat = Ubo2003ImageFormat::Hdr;
            else if (format == "exr")
                imageFormat = Ubo2003ImageFormat::Exr;
            else
                throw py::value_error("format must be one of jpg, png, hdr, exr, got '" + format +
                                      "'");
            SampleOptions options;
            options.width = options.height = size;
            options.variation = variation;
            options.threadsPerTile = weaveRepeats;
            auto btf = std::make_shared<MeasuredBtf>();
            {
                py::gil_scoped_release release;
                *btf = makeSampleBtf(options);
            }
            if (path.is_none()) return py::cast(PyBtf{btf, ""});
            const std::string file = py::str(path).cast<std::string>();
            {
                py::gil_scoped_release release;
                writeUbo2003Zip(*btf, file, imageFormat, quality);
            }
            return py::str(file);
        },
        py::arg("size") = 64, py::arg("variation") = 0.0f, py::arg("path") = py::none(),
        py::arg("format") = "jpg", py::arg("quality") = 95, py::arg("weave_repeats") = 2,
        "The built-in synthetic sample (`btf sample`): returned as a Btf in memory, or written "
        "as a UBO2003 zip to path (members jpg, png, hdr or exr), which is then returned.");

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

    const std::string fitDoc =
        "Fits a method to a measured BTF and returns the Material. Options are keyword "
        "arguments (max_exponent=... for option max-exponent), checked against the method's "
        "table: an unknown method or option, or a value out of range, raises ValueError with "
        "the registry's message. progress: callable(label, done, total), called from the "
        "fitting threads about ten times a second; returning False or raising stops the fit "
        "(KeyboardInterrupt, or what it raised). Ctrl-C stops the fit at its next progress "
        "step. The GIL is released while fitting. mipmap=True fits every mip level (`btf fit "
        "--mipmap`).\n\nThe methods and their options (as `btf fit --help`):\n\n" +
        methodsHelp();
    m.def(
        "fit",
        [](const PyBtf& btf, const std::string& methodName, const py::object& progress, bool mipmap,
           const py::kwargs& options) {
            const auto [method, fit] = checkedMethod(methodName, options);
            if (!method->fit)
                throw Error("method '" + method->name + "': fitting needs libosgBTFFit");
            FitScope scope(progress);
            const BtfSource& source = *btf.source;
            osg::ref_ptr<Material> material = scope.run([&, method = method, fit = fit] {
                const auto start = std::chrono::steady_clock::now();
                osg::ref_ptr<Material> fitted =
                    mipmap ? fitMipMapped(*method, source, fit) : method->fit(source, fit);
                fitted->fitInfo["seconds"] = std::to_string(
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
                        .count());
                if (!btf.path.empty()) fitted->fitInfo["source"] = btf.path;
                recordOptions(*fitted, *method, fit);
                return fitted;
            });
            return PyMaterial{material};
        },
        py::arg("btf"), py::arg("method"), py::kw_only(), py::arg("progress") = py::none(),
        py::arg("mipmap") = false, fitDoc.c_str());

    m.def(
        "error",
        [](const PyBtf& btf, const PyMaterial& m, long long errorTexels) {
            const Material& material = m.get();
            // A mip-mapped material is scored against every level's data, as `btf fit` does.
            std::unique_ptr<MipAtlasSource> atlas;
            if (material.mipLayout().mipMapped())
                atlas = std::make_unique<MipAtlasSource>(*btf.source);
            const BtfSource& source = atlas ? *atlas : *btf.source;
            if (material.width() != source.width() || material.height() != source.height() ||
                !(material.views() == source.views()) || !(material.lights() == source.lights()))
                throw py::value_error("the material is not of this BTF's size and directions");
            ErrorSummary e;
            {
                py::gil_scoped_release release;
                const std::size_t count = errorTexelCount(source, errorTexels);
                std::vector<std::size_t> subsample;
                if (count < source.texelCount()) subsample = randomTexels(source, count);
                e = computeError(
                    source,
                    [&](std::size_t texel, float* out) { material.evaluateMeasured(texel, out); },
                    subsample.empty() ? nullptr : &subsample);
            }
            return errorDict(e);
        },
        py::arg("btf"), py::arg("material"), py::arg("error_texels") = -1,
        "Meseth et al. 2003's per-texel error of a material against measured data (what `btf "
        "fit` prints): {average, minimum, maximum, rmse, psnr, texels, non_finite}. "
        "error_texels: a random subsample of that many texels (0: all; -1: all in memory, "
        "4096 of a UBO2014 file).");

    m.def(
        "error_of",
        [](const PyBtf& btf, const py::function& model, long long errorTexels,
           std::size_t batchTexels) {
            // A user's model, called with arrays of queries, scored by the same metric.
            const BtfSource& source = *btf.source;
            const std::size_t count = errorTexelCount(source, errorTexels);
            std::vector<std::size_t> subsample;
            if (count < source.texelCount()) subsample = randomTexels(source, count);
            const std::size_t V = source.viewCount(), L = source.lightCount();
            const std::size_t pairs = V * L;
            // The queries of one texel: uv at its centre, every measured (view, light) pair.
            py::array_t<float> views({py::ssize_t(pairs), py::ssize_t(3)});
            py::array_t<float> lights({py::ssize_t(pairs), py::ssize_t(3)});
            for (std::size_t p = 0; p < pairs; ++p) {
                const glm::vec3 a = source.views().vector(p / L), b = source.lights().vector(p % L);
                for (int c = 0; c < 3; ++c) {
                    views.mutable_data()[p * 3 + c] = a[c];
                    lights.mutable_data()[p * 3 + c] = b[c];
                }
            }
            // The model runs first for every texel (Python, with the GIL), then the metric.
            const std::vector<std::size_t> texelList = [&] {
                if (!subsample.empty()) return subsample;
                std::vector<std::size_t> all(source.texelCount());
                for (std::size_t t = 0; t < all.size(); ++t) all[t] = t;
                return all;
            }();
            checkMemory(std::uint64_t(texelList.size()) * pairs * 3 * sizeof(float),
                        "the model's values");
            std::vector<float> values(texelList.size() * pairs * 3);
            std::vector<std::size_t> slot(source.texelCount(), std::size_t(-1));
            const std::size_t batch = std::max<std::size_t>(1, batchTexels);
            for (std::size_t first = 0; first < texelList.size(); first += batch) {
                const std::size_t n = std::min(batch, texelList.size() - first);
                py::array_t<float> uv({py::ssize_t(n * pairs), py::ssize_t(2)});
                py::array_t<float> v({py::ssize_t(n * pairs), py::ssize_t(3)});
                py::array_t<float> l({py::ssize_t(n * pairs), py::ssize_t(3)});
                for (std::size_t k = 0; k < n; ++k) {
                    const std::size_t t = texelList[first + k];
                    slot[t] = first + k;
                    const float u =
                        (float(t % std::size_t(source.width())) + 0.5f) / float(source.width());
                    const float w =
                        (float(t / std::size_t(source.width())) + 0.5f) / float(source.height());
                    for (std::size_t p = 0; p < pairs; ++p) {
                        uv.mutable_data()[(k * pairs + p) * 2] = u;
                        uv.mutable_data()[(k * pairs + p) * 2 + 1] = w;
                    }
                    std::memcpy(v.mutable_data() + k * pairs * 3, views.data(),
                                pairs * 3 * sizeof(float));
                    std::memcpy(l.mutable_data() + k * pairs * 3, lights.data(),
                                pairs * 3 * sizeof(float));
                }
                const FloatArray result = FloatArray::ensure(model(uv, v, l));
                if (!result || result.size() != py::ssize_t(n * pairs * 3))
                    throw py::value_error("the model must return an (N, 3) array for N = " +
                                          std::to_string(n * pairs) + " queries");
                std::memcpy(values.data() + first * pairs * 3, result.data(),
                            n * pairs * 3 * sizeof(float));
            }
            ErrorSummary e;
            {
                py::gil_scoped_release release;
                e = computeError(
                    source,
                    [&](std::size_t texel, float* out) {
                        std::memcpy(out, values.data() + slot[texel] * pairs * 3,
                                    pairs * 3 * sizeof(float));
                    },
                    subsample.empty() ? nullptr : &subsample);
            }
            return errorDict(e);
        },
        py::arg("btf"), py::arg("model"), py::arg("error_texels") = -1,
        py::arg("batch_texels") = 64,
        "Scores a model written in Python with the same metric as error(): model(uv, views, "
        "lights) gets (N, 2) and two (N, 3) float32 arrays (every measured pair of a batch of "
        "texels, uv at the texel centres) and returns (N, 3) values.");

    m.def(
        "compare",
        [](const PyBtf& btf, const std::vector<std::string>& methodList, double holdoutFraction,
           const py::dict& methodOptions, const py::object& report, long long errorTexels,
           const py::object& progress) {
            std::vector<std::string> methods = methodList;
            if (methods.empty() || (methods.size() == 1 && methods[0] == "all"))
                methods = allCompareMethods();
            const std::string baseline = baselineMethod().name;
            if (std::find(methods.begin(), methods.end(), baseline) == methods.end())
                methods.insert(methods.begin(), baseline);
            std::map<std::string, FitOptions> fits;
            for (const std::string& name : methods) {
                py::dict options;
                if (methodOptions.contains(name)) options = methodOptions[py::str(name)];
                fits[name] = checkedMethod(name, options).second;
            }
            if (holdoutFraction < 0 || holdoutFraction > 0.5)
                throw py::value_error("holdout_fraction must be in 0..0.5, got " +
                                      std::to_string(holdoutFraction));
            const BtfSource& source = *btf.source;
            FitScope scope(progress);
            py::list rows;
            for (const std::string& name : methods) {
                const MethodInfo& method = findMethod(name);
                const FitOptions& fit = fits[name];
                py::dict row;
                row["method"] = name;
                py::dict options;
                for (const auto& [k, v] : fit.values()) options[py::str(k)] = v;
                row["options"] = options;
                struct Scores {
                    double fitSeconds = 0, average = 0, rmse = 0, psnr = 0, bytes = 0, values = 0;
                    std::uint64_t total = 0;
                    std::size_t texels = 0, heldOutPairs = 0;
                    double heldOutAverage = NAN, heldOutRmse = NAN, heldOutPsnr = NAN,
                           heldOutSsim = NAN;
                };
                try {
                    const Scores s = scope.run([&] {
                        // As `btf batch` scores a job (harness/batch/Job.cpp).
                        Scores s;
                        const auto start = std::chrono::steady_clock::now();
                        const osg::ref_ptr<Material> fitted = method.fit(source, fit);
                        s.fitSeconds =
                            std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
                                .count();
                        const std::size_t count = errorTexelCount(source, errorTexels);
                        std::vector<std::size_t> subsample;
                        if (count < source.texelCount()) subsample = randomTexels(source, count);
                        const auto* texels = subsample.empty() ? nullptr : &subsample;
                        const ErrorSummary e = computeError(
                            source,
                            [&](std::size_t t, float* out) { fitted->evaluateMeasured(t, out); },
                            texels);
                        s.average = e.average;
                        s.rmse = e.rmse;
                        s.psnr = e.psnr;
                        s.texels = e.texelsCompared;
                        const MemoryFootprint memory = fitted->memory();
                        s.bytes = memory.bytesPerTexel;
                        s.values = memory.valuesPerTexel;
                        s.total = memory.totalBytes;
                        if (holdoutFraction > 0) {
                            const batch::HoldoutSplit split = batch::holdoutSplit(
                                source.viewCount(), source.lightCount(), holdoutFraction);
                            const batch::DirectionSubsetSource kept(source, split);
                            const osg::ref_ptr<Material> without = method.fit(kept, fit);
                            const HeldOutScores h = scoreHeldOut(source, *without, split, texels);
                            s.heldOutAverage = h.error.average;
                            s.heldOutRmse = h.error.rmse;
                            s.heldOutPsnr = h.error.psnr;
                            s.heldOutSsim = h.ssim;
                            s.heldOutPairs = h.pairs;
                        }
                        return s;
                    });
                    row["failed"] = false;
                    row["failure"] = "";
                    row["fit_seconds"] = s.fitSeconds;
                    row["average"] = s.average;
                    row["rmse"] = s.rmse;
                    row["psnr"] = numberOrNan(s.psnr);
                    row["error_texels"] = s.texels;
                    row["bytes_per_texel"] = s.bytes;
                    row["values_per_texel"] = s.values;
                    row["total_bytes"] = s.total;
                    row["compression_ratio"] =
                        double(source.imageCount() * 3) / std::max(s.bytes, 1e-30);
                    row["held_out_average"] = s.heldOutAverage;
                    row["held_out_rmse"] = s.heldOutRmse;
                    row["held_out_psnr"] = numberOrNan(s.heldOutPsnr);
                    row["held_out_ssim"] = s.heldOutSsim;
                    row["held_out_pairs"] = s.heldOutPairs;
                } catch (const Error& e) {
                    // A method that fails is a row saying why, as in `btf compare`.
                    row["failed"] = true;
                    row["failure"] = std::string(e.what());
                    for (const char* key :
                         {"fit_seconds", "average", "rmse", "psnr", "bytes_per_texel",
                          "values_per_texel", "compression_ratio", "held_out_average",
                          "held_out_rmse", "held_out_psnr", "held_out_ssim"})
                        row[key] = std::numeric_limits<double>::quiet_NaN();
                }
                rows.append(row);
            }
            if (!report.is_none()) {
                if (btf.path.empty())
                    throw py::value_error(
                        "report needs a BTF loaded from a file (btf compare reads it again); "
                        "write the sample with osgbtf.sample(path=...) and load that");
                CompareOptions options;
                options.input = btf.path;
                options.outputDir = py::str(report).cast<std::string>();
                options.methods = methods;
                for (const auto& [name, fit] : fits)
                    for (const auto& [k, v] : fit.values()) options.methodOptions[name][k] = v;
                options.fitTool = findBtfTool();
                options.errorTexels = errorTexels;
                options.holdoutFraction = holdoutFraction;
                scope.run([&] {
                    runCompare(options);
                    return 0;
                });
            }
            return rows;
        },
        py::arg("btf"), py::arg("methods") = std::vector<std::string>{"all"},
        py::arg("holdout_fraction") = 0.1, py::arg("options") = py::dict(),
        py::arg("report") = py::none(), py::arg("error_texels") = -1,
        py::arg("progress") = py::none(),
        "Fits each method (the baseline added first) and scores it as `btf batch` scores a job: "
        "a list of dicts (method, options, failed, failure, fit_seconds, average, rmse, psnr, "
        "error_texels, bytes_per_texel, values_per_texel, total_bytes, compression_ratio and, "
        "with holdout_fraction > 0, held_out_average/rmse/psnr/ssim/pairs: the error, PSNR and "
        "SSIM on directions left out of a second fit), which pandas.DataFrame takes as it is. "
        "options: {method: "
        "{option: value}}. report=DIR also runs `btf compare` into DIR (report.md, "
        "results.csv/json, pictures; the btf executable fits in child processes).");

    m.attr("__version__") = "0.1.0";
}

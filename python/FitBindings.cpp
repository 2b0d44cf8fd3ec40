// osgbtf: fitting and scoring (fit, error, error_of, compare). Fits through the method registry
// (options checked by validateOptions; progress and cancellation through core/Progress's
// observer, without the GIL), scored by harness/FitScore.h as `btf fit` and `btf batch` score
// theirs.
#include <dlfcn.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/ErrorMetrics.h"
#include "core/MipPyramid.h"
#include "core/Progress.h"
#include "fit/MipMapping.h"
#include "harness/Compare.h"
#include "harness/FitRunner.h"
#include "harness/FitScore.h"
#include "materials/MethodOptions.h"
#include "materials/MethodRegistry.h"
#include "python/Bindings.h"

namespace osgBTF::python {

namespace {

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
    using namespace py::literals;
    return py::dict("average"_a = e.average, "minimum"_a = e.minimum, "maximum"_a = e.maximum,
                    "rmse"_a = e.rmse, "psnr"_a = e.psnr, "texels"_a = e.texelsCompared,
                    "non_finite"_a = e.nonFiniteValues);
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

void bindFitting(py::module_& m) {
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
                e = fitError(source, material, errorSubsample(source, errorTexels));
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
            const std::vector<std::size_t> subsample = errorSubsample(source, errorTexels);
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
                try {
                    const MethodScore s = scope.run([&] {
                        return fitAndScore(source, method, fit, errorTexels, holdoutFraction);
                    });
                    row["failed"] = false;
                    row["failure"] = "";
                    row["fit_seconds"] = s.fitSeconds;
                    row["average"] = s.fit.error.average;
                    row["rmse"] = s.fit.error.rmse;
                    row["psnr"] = numberOrNan(s.fit.error.psnr);
                    row["error_texels"] = s.fit.error.texelsCompared;
                    row["bytes_per_texel"] = s.fit.memory.bytesPerTexel;
                    row["values_per_texel"] = s.fit.memory.valuesPerTexel;
                    row["total_bytes"] = s.fit.memory.totalBytes;
                    row["compression_ratio"] = s.fit.compressionRatio;
                    const double nan = std::numeric_limits<double>::quiet_NaN();
                    row["held_out_average"] = s.heldOut ? s.heldOut->error.average : nan;
                    row["held_out_rmse"] = s.heldOut ? s.heldOut->error.rmse : nan;
                    row["held_out_psnr"] = s.heldOut ? numberOrNan(s.heldOut->error.psnr) : nan;
                    row["held_out_ssim"] = s.heldOut ? s.heldOut->ssim : nan;
                    row["held_out_pairs"] = s.heldOut ? s.heldOut->pairs : std::size_t(0);
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
}

}  // namespace osgBTF::python

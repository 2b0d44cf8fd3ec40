// osgbtf: measured BTFs (osgbtf.Btf, load, memory_limit, sample). Through openBtfSource: a
// UBO2014 file stays factored, decoded block by block on demand. Arrays are written by C++
// straight into the numpy buffers they are returned in.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/MeasuredBtf.h"
#include "harness/sample/SampleBtf.h"
#include "harness/sample/Ubo2003Writer.h"
#include "loaders/LoadBtf.h"
#include "python/Bindings.h"

namespace osgBTF::python {

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

namespace {

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

}  // namespace

void bindMeasuredBtfs(py::module_& m) {
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
}

}  // namespace osgBTF::python

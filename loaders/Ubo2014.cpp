#include "loaders/Ubo2014.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <Imath/half.h>

#include "core/Error.h"
#include "core/FloatImage.h"

namespace osgBTF {

namespace {

namespace fs = std::filesystem;

constexpr double kRadiansPerHalfTurn = 3.14159265358979323846;

/** Little-endian reader that knows the file size, so every read names the field that ran past the
 *  end and bulk data can be checked against the bytes that remain before allocating for it. */
class Reader {
public:
    explicit Reader(const std::string& path) : _path(path) {
        _in.open(path, std::ios::binary);
        if (!_in) fail(path, std::string("cannot open: ") + std::strerror(errno));
        _in.seekg(0, std::ios::end);
        _size = std::uint64_t(_in.tellg());
        _in.seekg(0);
    }

    std::uint64_t position() const { return _pos; }
    std::uint64_t size() const { return _size; }
    std::uint64_t remaining() const { return _size - _pos; }
    const std::string& path() const { return _path; }

    void read(void* data, std::uint64_t n, const std::string& field) {
        if (n > remaining()) fail(_path, "unexpected end of file while reading " + field);
        _in.read(static_cast<char*>(data), std::streamsize(n));
        if (!_in) fail(_path, "read error while reading " + field);
        _pos += n;
    }
    void seek(std::uint64_t offset) {
        _in.clear();
        _in.seekg(std::streamoff(offset));
        _pos = offset;
    }
    template <typename T>
    T get(const std::string& field) {
        // The format is little-endian and so is every platform osgBTF builds on.
        T value;
        read(&value, sizeof(T), field);
        return value;
    }
    std::uint32_t u32(const std::string& field) { return get<std::uint32_t>(field); }
    float f32(const std::string& field) { return get<float>(field); }
    std::string chars(std::uint64_t n, const std::string& field) {
        need(n, field);
        std::string text(n, '\0');
        read(text.data(), n, field);
        return text;
    }
    /** Fails before allocating when the header announces more data than the file holds. */
    void need(long double bytes, const std::string& field) const {
        if (bytes > (long double)remaining()) {
            std::ostringstream problem;
            problem << "unexpected end of file while reading " << field << ": the header announces "
                    << std::fixed << std::setprecision(0) << bytes << " bytes but only "
                    << remaining() << " remain (truncated or corrupt file)";
            fail(_path, problem.str());
        }
    }

private:
    std::string _path;
    std::ifstream _in;
    std::uint64_t _size = 0, _pos = 0;
};

/** Reads rows x stride scalars, keeping the first `use` of each row. With `skip` (a header-only
 *  read) it only moves past them and gives an empty matrix of `use` columns. With `sink`, the rows
 * go to it chunk by chunk as the file stores them (factor `factor` of the file) and the matrix
 *  returned has 0 rows. */
FactorMatrix readMatrix(Reader& in, std::uint64_t rows, std::uint64_t stride, std::uint64_t use,
                        int scalarSize, const std::string& field, bool skip = false,
                        TexelFactorSink* sink = nullptr, int factor = 0) {
    // Nothing to keep per row (rank 0 factors, an empty height map): the rows are skipped, not
    // walked; a header can claim billions of them (fuzz/regression/ubo2014/).
    if (skip || use == 0) {
        in.need((long double)rows * stride * scalarSize, field);
        in.seek(in.position() + rows * stride * std::uint64_t(scalarSize));
        return FactorMatrix(skip ? 0 : static_cast<Eigen::Index>(rows),
                            static_cast<Eigen::Index>(use));
    }
    FactorMatrix m(static_cast<Eigen::Index>(sink ? 0 : rows), static_cast<Eigen::Index>(use));
    const std::uint64_t rowBytes = stride * std::uint64_t(scalarSize);
    const std::uint64_t rowsPerChunk =
        std::max<std::uint64_t>(1, (4u << 20) / std::max<std::uint64_t>(rowBytes, 1));
    std::vector<unsigned char> chunk;
    for (std::uint64_t r0 = 0; r0 < rows; r0 += rowsPerChunk) {
        const std::uint64_t n = std::min(rowsPerChunk, rows - r0);
        chunk.resize(n * rowBytes);
        in.read(chunk.data(), chunk.size(), field);
        if (sink) {
            sink->texelRows(factor, int(use), r0, n, chunk.data(), rowBytes, scalarSize);
            continue;
        }
        for (std::uint64_t r = 0; r < n; ++r)
            scalarsToFloats(chunk.data() + r * rowBytes, use, scalarSize,
                            m.data() + (r0 + r) * use);  // row-major
    }
    return m;
}

Eigen::VectorXf readVector(Reader& in, std::uint64_t count, std::uint64_t use, int scalarSize,
                           const std::string& field) {
    const FactorMatrix row = readMatrix(in, 1, count, use, scalarSize, field);
    return row.row(0).transpose();
}

int checkScalarSize(const std::string& path, unsigned value, const std::string& where) {
    if (value != 2 && value != 4 && value != 8)
        fail(path, where + ": scalar size " + std::to_string(value) +
                       " is not 2 (half), 4 (float) or 8 (double)");
    return int(value);
}

/** Allocation guard for one factor matrix pair: the memory limit first (the user's explicit bound),
 *  then the bytes really present in the file. */
void guardFactors(const Reader& in, std::uint64_t rows, std::uint64_t cols, std::uint64_t stride,
                  std::uint64_t use, int scalarSize, const std::string& what) {
    const long double floats = ((long double)rows + cols + 1) * use;
    const long double bytes = floats * 4;
    checkMemory(bytes > 1.8e19L ? UINT64_MAX : std::uint64_t(bytes), in.path() + ": " + what);
    in.need(((long double)rows + cols + 1) * stride * scalarSize, what);
}

Direction toDirection(float thetaRadians, float phiRadians, const std::string& path,
                      const std::string& field) {
    if (!std::isfinite(thetaRadians) || !std::isfinite(phiRadians))
        fail(path, field + " is not a finite angle");
    // Rounded to 1e-4 degrees so the float radians of e.g. 60 degrees read back as 60.
    auto clean = [](double degrees) { return float(std::round(degrees * 1e4) / 1e4); };
    double theta = double(thetaRadians) * 180.0 / kRadiansPerHalfTurn;
    double phi = std::fmod(double(phiRadians) * 180.0 / kRadiansPerHalfTurn, 360.0);
    if (phi < 0) phi += 360.0;
    Direction d{clean(theta), clean(phi)};
    if (d.phi >= 360.0f) d.phi -= 360.0f;
    if (d.theta < -1e-3f || d.theta > 90.001f)
        fail(path, field + ": theta " + std::to_string(d.theta) + " degrees is outside [0, 90]");
    return d;
}

struct Signature {
    const char* text;
    FactorModel model;
    bool extended;
    bool rotations;
};

const Signature kSignatures[] = {
    {"!DFMF08FCR", FactorModel::Dfmf, false, true}, {"!DFMF08FC", FactorModel::Dfmf, false, false},
    {"!FMF12FCER", FactorModel::Fmf, true, true},   {"!FMF12FCE", FactorModel::Fmf, true, false},
    {"!FMF06FCR", FactorModel::Fmf, false, true},   {"!FMF06FC", FactorModel::Fmf, false, false},
};

std::string showBytes(const std::string& bytes) {
    std::ostringstream out;
    out << '"';
    for (unsigned char c : bytes) out << (c >= 32 && c < 127 ? char(c) : '.');
    out << "\" (bytes";
    for (unsigned char c : bytes)
        out << ' ' << std::hex << std::setw(2) << std::setfill('0') << int(c);
    out << ')';
    return out.str();
}

/** Picks the signature. An R-less signature followed by a Size whose low byte is 'R' (0x52) is
 *  ambiguous; the reading whose meta block looks sane (Size >= 264, Version 1..4) wins. */
const Signature& readSignature(Reader& in) {
    std::string head(std::min<std::uint64_t>(in.size(), 32), '\0');
    in.read(head.data(), head.size(), "the signature");
    auto plausibleMeta = [&](std::size_t offset) {
        if (head.size() < offset + 8) return false;
        std::uint32_t size, version;
        std::memcpy(&size, head.data() + offset, 4);
        std::memcpy(&version, head.data() + offset + 4, 4);
        return size >= 264 && size < in.size() && version >= 1 && version <= 4;
    };
    const Signature* match = nullptr;
    for (const Signature& s : kSignatures) {
        const std::size_t n = std::strlen(s.text);
        if (head.compare(0, n, s.text) != 0) continue;
        if (match && !plausibleMeta(std::strlen(match->text)) && plausibleMeta(n)) match = &s;
        if (!match) match = &s;
    }
    if (match) {
        in.seek(std::strlen(match->text));
        return *match;
    }
    const std::string first = head.substr(0, 10);
    if (head.rfind("!PVF", 0) == 0)
        fail(in.path(), "PVF (per-view PCA) .btf files are not supported (signature " +
                            showBytes(first) + ")");
    if (head.rfind("!BDIF", 0) == 0)
        fail(in.path(), "BDI (raw half-float images) .btf files are not supported (signature " +
                            showBytes(first) + ")");
    fail(in.path(), "unknown signature " + showBytes(first) +
                        "; expected !DFMF08FCR, !FMF12FCER, !FMF06FCR or their forms without R");
}

void readMeta(Reader& in, Ubo2014Factors& f) {
    const std::uint64_t start = in.position();
    const std::uint32_t size = in.u32("meta-data Size");
    f.metaVersion = in.u32("meta-data Version");
    if (f.metaVersion < 1 || f.metaVersion > 4)
        fail(in.path(),
             "meta-data version " + std::to_string(f.metaVersion) + " is not supported (1 to 4)");
    auto text = [&](const char* field) {
        std::string s = in.chars(80, field);
        return s.substr(0, s.find('\0'));
    };
    f.measurementSetup = text("measurement setup");
    f.imageSensor = text("image sensor");
    f.lightSource = text("light source");
    f.ppmm = in.f32("ppmm");
    for (float& s : f.rgbScale) s = in.f32("rgb scale factor");
    f.cosine = f.metaVersion > 1 ? in.u32("cosine flag") != 0 : false;
    if (f.metaVersion > 2) {
        const std::uint32_t length = in.u32("XML length");
        f.xml = in.chars(length, "XML");
    }
    if (f.metaVersion > 3) {
        const std::uint32_t channels = in.u32("channel count");
        in.need((long double)channels * 4, "channel names");
        f.channelNames.clear();
        for (std::uint32_t c = 0; c < channels; ++c) {
            const std::uint32_t length = in.u32("channel name length");
            f.channelNames.push_back(in.chars(length, "channel name"));
        }
    }
    const std::uint64_t actual = in.position() - start;
    if (actual != size)
        fail(in.path(), "meta-data Size field says " + std::to_string(size) +
                            " bytes but the meta-data block (version " +
                            std::to_string(f.metaVersion) + ") holds " + std::to_string(actual));
    if (f.channelNames.size() != 3) {
        std::string names;
        for (const std::string& n : f.channelNames) names += (names.empty() ? "" : ",") + n;
        fail(in.path(), std::to_string(f.channelNames.size()) + " colour channels (" + names +
                            ") are not supported; only 3");
    }
}

void readDirections(Reader& in, Ubo2014Factors& f) {
    const std::uint32_t nV = in.u32("view count");
    if (nV == 0) fail(in.path(), "the file lists no views");
    in.need((long double)nV * 12, "view directions");
    std::vector<Direction> views, lights;
    std::uint32_t nL = 0;
    for (std::uint32_t v = 0; v < nV; ++v) {
        const std::string view = "view " + std::to_string(v);
        const float theta = in.f32(view + " theta"), phi = in.f32(view + " phi");
        views.push_back(toDirection(theta, phi, in.path(), view));
        const std::uint32_t count = in.u32(view + " light count");
        if (v == 0) {
            if (count == 0) fail(in.path(), "the file lists no lights");
            nL = count;
        } else if (count != nL) {
            fail(in.path(), view + " lists " + std::to_string(count) + " lights but view 0 lists " +
                                std::to_string(nL));
        }
        in.need((long double)count * 8, view + " light directions");
        for (std::uint32_t l = 0; l < count; ++l) {
            const std::string light = view + " light " + std::to_string(l);
            const float lt = in.f32(light + " theta"), lp = in.f32(light + " phi");
            // Later views repeat the list; the readers of the format keep the first.
            if (v == 0) lights.push_back(toDirection(lt, lp, in.path(), light));
        }
    }
    const std::string stem = fs::path(in.path()).stem().string();
    f.views = DirectionSet(stem + "-views", std::move(views));
    f.lights = DirectionSet(stem + "-lights", std::move(lights));

    const std::uint32_t width = in.u32("width"), height = in.u32("height");
    if (width == 0 || height == 0 || width > 0x7fffffffu || height > 0x7fffffffu)
        fail(in.path(),
             "invalid texel size " + std::to_string(width) + "x" + std::to_string(height));
    f.width = int(width);
    f.height = int(height);
    if (f.hasRotations) {
        const std::uint32_t count = in.u32("rotation count");
        in.need((long double)count * 36, "rotations");
        f.rotations.resize(count);
        for (auto& r : f.rotations)
            for (float& v : r) v = in.f32("rotations");
    }
}

void readDfmf(Reader& in, Ubo2014Factors& f, bool headerOnly, TexelFactorSink* sink) {
    f.maxComponents = in.u32("maximum component count");
    f.colorModel = in.get<std::int32_t>("colour model");
    FactoredBtf::checkColorModel(in.path(), f.colorModel);
    for (float& v : f.colorMean) v = in.f32("colour mean");
    for (float& v : f.colorMatrix) v = in.f32("colour matrix");
    const std::uint64_t abrdfs = std::uint64_t(f.views.size()) * f.lights.size();
    const std::uint64_t texels = std::uint64_t(f.width) * std::uint64_t(f.height);
    for (int c = 0; c < 3; ++c) {
        const std::string channel = "channel " + std::to_string(c);
        const int scalarSize =
            checkScalarSize(in.path(), in.get<std::uint8_t>(channel + " scalar size"), channel);
        if (c == 0) f.scalarSize = scalarSize;
        const std::uint32_t k = in.u32(channel + " component count");
        const std::uint32_t rows = in.u32(channel + " U row count");
        const std::uint32_t cols = in.u32(channel + " SxV row count");
        // btflib also accepts the transposed arrangement (U over texels); swap it back.
        const bool transposed =
            !(rows == abrdfs && cols == texels) && rows == texels && cols == abrdfs;
        if (!transposed && !(rows == abrdfs && cols == texels))
            fail(in.path(), channel + ": U has " + std::to_string(rows) + " rows and SxV " +
                                std::to_string(cols) +
                                "; expected views*lights = " + std::to_string(abrdfs) +
                                " and width*height = " + std::to_string(texels));
        if (!headerOnly) guardFactors(in, rows, cols, k, k, scalarSize, channel + " factors");
        in.need(((long double)rows + cols + 1) * k * scalarSize, channel + " factors");
        BtfFactor factor;
        factor.S = readVector(in, k, k, scalarSize, channel + " S");
        if (sink) sink->beginFactor(f, c, int(k), scalarSize);
        // The texel factor (SxV; U in the transposed arrangement) goes to the sink if any.
        factor.U = readMatrix(in, rows, k, k, scalarSize, channel + " U", headerOnly,
                              transposed ? sink : nullptr, c);
        factor.SxV = readMatrix(in, cols, k, k, scalarSize, channel + " SxV", headerOnly,
                                transposed ? nullptr : sink, c);
        if (transposed) std::swap(factor.U, factor.SxV);
        f.factors.push_back(std::move(factor));
    }
}

void readFmf(Reader& in, Ubo2014Factors& f, bool headerOnly, TexelFactorSink* sink) {
    f.headerVersion = f.extendedHeader ? in.get<std::uint8_t>("FMF header version") : 0;
    if (f.headerVersion >= 3)
        fail(in.path(), "FMF header version " + std::to_string(f.headerVersion) +
                            " is not supported (0 to 2)");
    if (f.headerVersion >= 1) f.dynamicRangeReduction = in.u32("dynamic range reduction");
    if (f.headerVersion >= 2) {
        const std::uint32_t w = in.u32("height map width"), h = in.u32("height map height");
        const long double count = (long double)w * h;
        checkMemory(count * 4 > 1.8e19L ? UINT64_MAX : std::uint64_t(count * 4),
                    in.path() + ": height map of " + std::to_string(w) + "x" + std::to_string(h));
        in.need(count * 2, "height map");
        f.heightMapWidth = int(w);
        f.heightMapHeight = int(h);
        const FactorMatrix values = readMatrix(in, h, w, w, 2, "height map");
        f.heightMap.assign(values.data(), values.data() + values.size());
    }
    const std::uint32_t kUsed = in.u32("component count");
    const int scalarSize = checkScalarSize(in.path(), in.get<std::uint8_t>("scalar size"), "FMF");
    f.scalarSize = scalarSize;
    const std::uint32_t stride = in.u32("stored component count");
    const std::uint32_t rows = in.u32("U row count"), cols = in.u32("SxV row count");
    const std::uint64_t abrdfRows = std::uint64_t(f.views.size()) * f.lights.size() * 3;
    const std::uint64_t texels = std::uint64_t(f.width) * std::uint64_t(f.height);
    if (rows == texels * 3 && cols == abrdfRows / 3 && !(rows == abrdfRows && cols == texels))
        fail(in.path(), "the transposed FMF layout (U over colour texels) is not supported");
    if (rows != abrdfRows || cols != texels)
        fail(in.path(), "U has " + std::to_string(rows) + " rows and SxV " + std::to_string(cols) +
                            "; expected views*lights*3 = " + std::to_string(abrdfRows) +
                            " and width*height = " + std::to_string(texels));
    // btflib: K_b is the stride of every row and the length of S; the first min(K_a, K_b) count.
    const std::uint32_t use = std::min(kUsed, stride);
    if (!headerOnly) guardFactors(in, rows, cols, stride, use, scalarSize, "factors");
    in.need(((long double)rows + cols + 1) * stride * scalarSize, "factors");
    BtfFactor factor;
    factor.S = readVector(in, stride, use, scalarSize, "S");
    factor.U = readMatrix(in, rows, stride, use, scalarSize, "U", headerOnly);
    if (sink) sink->beginFactor(f, 0, int(use), scalarSize);
    factor.SxV = readMatrix(in, cols, stride, use, scalarSize, "SxV", headerOnly, sink, 0);
    f.factors.push_back(std::move(factor));
}

void put(std::string& out, const void* data, std::size_t n) {
    out.append(static_cast<const char*>(data), n);
}
template <typename T>
void put(std::string& out, T value) {
    put(out, &value, sizeof value);
}
void putScalar(std::string& out, float v, int scalarSize) {
    if (scalarSize == 2)
        put(out, Imath::half(v).bits());
    else if (scalarSize == 8)
        put(out, double(v));
    else
        put(out, v);
}
void putMatrix(std::string& out, const FactorMatrix& m, int scalarSize) {
    for (Eigen::Index r = 0; r < m.rows(); ++r)
        for (Eigen::Index c = 0; c < m.cols(); ++c) putScalar(out, m(r, c), scalarSize);
}
void putChars(std::string& out, const std::string& text, std::size_t width) {
    std::string field = text.substr(0, width);
    field.resize(width, '\0');
    out += field;
}
void putAngle(std::string& out, const Direction& d) {
    put(out, float(d.theta * kRadiansPerHalfTurn / 180.0));
    // Azimuths as btflib writes them, atan2-style in (-pi, pi].
    const double phi = d.phi > 180.0f ? d.phi - 360.0 : d.phi;
    put(out, float(phi * kRadiansPerHalfTurn / 180.0));
}

}  // namespace

Ubo2014Factors readUbo2014(const std::string& path, const LoadOptions& options) {
    Reader in(path);
    if (in.size() == 0) fail(path, "file is empty");
    Ubo2014Factors f;
    f.source = path;
    const Signature& signature = readSignature(in);
    f.signature = signature.text;
    f.model = signature.model;
    f.extendedHeader = signature.extended;
    f.hasRotations = signature.rotations;
    readMeta(in, f);
    readDirections(in, f);
    TexelFactorSink* sink = options.headerOnly ? nullptr : options.texelFactors;
    if (f.model == FactorModel::Dfmf)
        readDfmf(in, f, options.headerOnly, sink);
    else
        readFmf(in, f, options.headerOnly, sink);
    if (in.remaining() != 0)
        fail(path, std::to_string(in.remaining()) +
                       " unexpected trailing bytes after the last factor matrix");
    return f;
}

MeasuredBtf decodeUbo2014(const Ubo2014Factors& f, const LoadOptions& options) {
    const std::string label = options.progressLabel.empty()
                                  ? "decoding " + fs::path(f.source).filename().string()
                                  : options.progressLabel;
    return f.decode(options.storage, label);
}

MeasuredBtf loadUbo2014(const std::string& path, const LoadOptions& options) {
    const Ubo2014Factors factors = readUbo2014(path, options);
    return decodeUbo2014(factors, options);
}

void writeUbo2014(const Ubo2014Factors& f, const std::string& path) {
    const bool fmf = f.model == FactorModel::Fmf;
    if (f.scalarSize != 2 && f.scalarSize != 4 && f.scalarSize != 8)
        fail(path, "cannot write scalar size " + std::to_string(f.scalarSize));
    if (f.metaVersion < 1 || f.metaVersion > 4)
        fail(path, "cannot write meta-data version " + std::to_string(f.metaVersion));
    if (f.factors.size() != (fmf ? 1u : 3u))
        fail(path, std::string("cannot write: ") + (fmf ? "FMF needs 1" : "DFMF needs 3") +
                       " factor sets, got " + std::to_string(f.factors.size()));
    std::string out;
    if (fmf)
        out = f.extendedHeader ? "!FMF12FCE" : "!FMF06FC";
    else
        out = "!DFMF08FC";
    if (f.hasRotations) out += 'R';

    std::string meta;
    put(meta, f.metaVersion);
    putChars(meta, f.measurementSetup, 80);
    putChars(meta, f.imageSensor, 80);
    putChars(meta, f.lightSource, 80);
    put(meta, f.ppmm);
    for (float s : f.rgbScale) put(meta, s);
    if (f.metaVersion > 1) put(meta, std::uint32_t(f.cosine ? 1 : 0));
    if (f.metaVersion > 2) {
        put(meta, std::uint32_t(f.xml.size()));
        meta += f.xml;
    }
    if (f.metaVersion > 3) {
        put(meta, std::uint32_t(f.channelNames.size()));
        for (const std::string& name : f.channelNames) {
            put(meta, std::uint32_t(name.size()));
            meta += name;
        }
    }
    put(out, std::uint32_t(meta.size() + 4));
    out += meta;

    put(out, std::uint32_t(f.views.size()));
    for (std::size_t v = 0; v < f.views.size(); ++v) {
        putAngle(out, f.views[v]);
        put(out, std::uint32_t(f.lights.size()));
        for (std::size_t l = 0; l < f.lights.size(); ++l) putAngle(out, f.lights[l]);
    }
    put(out, std::uint32_t(f.width));
    put(out, std::uint32_t(f.height));
    if (f.hasRotations) {
        put(out, std::uint32_t(f.rotations.size()));
        for (const auto& r : f.rotations)
            for (float v : r) put(out, v);
    }

    auto putFactor = [&](const BtfFactor& factor) {
        const Eigen::Index k = factor.U.cols();
        for (Eigen::Index i = 0; i < k; ++i)
            putScalar(out, i < factor.S.size() ? factor.S[i] : 1.0f, f.scalarSize);
        putMatrix(out, factor.U, f.scalarSize);
        putMatrix(out, factor.SxV, f.scalarSize);
    };
    if (fmf) {
        if (f.extendedHeader) {
            put(out, std::uint8_t(f.headerVersion));
            if (f.headerVersion >= 1) put(out, f.dynamicRangeReduction);
            if (f.headerVersion >= 2) {
                put(out, std::uint32_t(f.heightMapWidth));
                put(out, std::uint32_t(f.heightMapHeight));
                for (float h : f.heightMap) put(out, Imath::half(h).bits());
            }
        }
        const BtfFactor& factor = f.factors[0];
        put(out, std::uint32_t(factor.U.cols()));
        put(out, std::uint8_t(f.scalarSize));
        put(out, std::uint32_t(factor.U.cols()));
        put(out, std::uint32_t(factor.U.rows()));
        put(out, std::uint32_t(factor.SxV.rows()));
        putFactor(factor);
    } else {
        put(out, f.maxComponents);
        put(out, std::int32_t(f.colorModel));
        for (float v : f.colorMean) put(out, v);
        for (float v : f.colorMatrix) put(out, v);
        for (const BtfFactor& factor : f.factors) {
            put(out, std::uint8_t(f.scalarSize));
            put(out, std::uint32_t(factor.U.cols()));
            put(out, std::uint32_t(factor.U.rows()));
            put(out, std::uint32_t(factor.SxV.rows()));
            putFactor(factor);
        }
    }

    // A temporary name per process: two writers of one path never share (and truncate) one.
    writeFileAtomically(path, [&](const std::string& tmp) {
        std::ofstream file(tmp, std::ios::binary);
        file.write(out.data(), std::streamsize(out.size()));
        file.close();
        if (!file) fail(path, "cannot write " + tmp);
    });
}

void writeFactorsAsUbo2014(const FactoredBtf& factors, const std::string& path, int scalarSize,
                           const Ubo2014Factors* meta) {
    if (scalarSize != 2 && scalarSize != 4)
        fail(path,
             "cannot write scalar size " + std::to_string(scalarSize) + " (2 half or 4 float)");
    factors.validate();
    Ubo2014Factors f;
    if (meta) {
        f.measurementSetup = meta->measurementSetup;
        f.imageSensor = meta->imageSensor;
        f.lightSource = meta->lightSource;
        f.ppmm = meta->ppmm;
        f.rgbScale = meta->rgbScale;
        f.xml = meta->xml;
    }
    static_cast<FactoredBtf&>(f) = factors;
    f.metaVersion = 4;
    f.channelNames = {"R", "G", "B"};
    f.hasRotations = false;
    f.scalarSize = scalarSize;
    if (f.model == FactorModel::Fmf) {
        f.extendedHeader = true;
        f.headerVersion = 1;  // the DRR field, no height map
    } else {
        int k = 0;
        for (const BtfFactor& factor : f.factors) k = std::max(k, int(factor.U.cols()));
        f.maxComponents = std::uint32_t(k);
    }
    writeUbo2014(f, path);
}

}  // namespace osgBTF

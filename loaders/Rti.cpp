#include "loaders/Rti.h"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <glm/geometric.hpp>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "core/SizeGuard.h"
#include "loaders/ImageSet.h"
#include "loaders/OutOfCoreImageSet.h"
#include "loaders/Ubo2003.h"

namespace osgBTF {

namespace {

namespace fs = std::filesystem;

bool endsWithLp(const std::string& name) {
    return name.size() > 3 && asciiLower(name.substr(name.size() - 3)) == ".lp";
}

/** The fields of a line separated by blanks (spaces, tabs, a trailing CR). */
std::vector<std::string> fields(const std::string& line) {
    std::vector<std::string> out;
    std::istringstream in(line);
    for (std::string field; in >> field;) out.push_back(field);
    return out;
}

bool parseLpNumber(const std::string& text, double& value) {
    if (text.empty()) return false;
    char* end = nullptr;
    value = std::strtod(text.c_str(), &end);
    return end == text.c_str() + text.size() && std::isfinite(value);
}

/** `image` as a path relative to the .lp file's folder, '\\' read as '/'; "" when absolute. */
std::string relativeName(std::string image) {
    for (char& c : image)
        if (c == '\\') c = '/';
    if (!image.empty() && image[0] == '/') return "";
    if (image.size() > 1 && image[1] == ':') return "";  // a Windows drive
    while (image.rfind("./", 0) == 0) image = image.substr(2);
    return image;
}

std::string extensionOf(const std::string& name) {
    const std::string base = imageSetBasename(name);
    const auto dot = base.find_last_of('.');
    return dot == std::string::npos ? "" : asciiLower(base.substr(dot + 1));
}

}  // namespace

std::vector<RtiLight> parseLightPositions(const std::string& text, const std::string& lpPath) {
    std::vector<RtiLight> lights;
    std::istringstream in(text);
    std::string line;
    int lineNumber = 0;
    long long count = -1;
    int countLine = 0;
    std::map<std::string, int> seen;  // image -> line
    auto where = [&](int n) { return lpPath + ":" + std::to_string(n); };
    while (std::getline(in, line)) {
        ++lineNumber;
        const std::vector<std::string> f = fields(line);
        if (f.empty()) continue;
        if (count < 0) {
            double value = 0;
            if (f.size() != 1 || !parseLpNumber(f[0], value) || value != std::floor(value) ||
                value < 1 || value > 1e6)
                fail(where(lineNumber), "the first line must be the number of images, got '" +
                                            line.substr(0, 40) + "'");
            count = (long long)value;
            countLine = lineNumber;
            continue;
        }
        if (f.size() < 4)
            fail(where(lineNumber), "expected 'IMAGE X Y Z', got '" + line.substr(0, 80) + "'");
        double xyz[3];
        for (int i = 0; i < 3; ++i)
            if (!parseLpNumber(f[f.size() - 3 + std::size_t(i)], xyz[i]))
                fail(where(lineNumber), "'" + f[f.size() - 3 + std::size_t(i)] +
                                            "' is not a number (expected 'IMAGE X Y Z')");
        // The name is everything before the three numbers, spaces included.
        std::size_t end = line.size();
        for (int i = 0; i < 3; ++i) {
            while (end > 0 && std::isspace(static_cast<unsigned char>(line[end - 1]))) --end;
            while (end > 0 && !std::isspace(static_cast<unsigned char>(line[end - 1]))) --end;
        }
        std::size_t begin = 0;
        while (begin < end && std::isspace(static_cast<unsigned char>(line[begin]))) ++begin;
        while (end > begin && std::isspace(static_cast<unsigned char>(line[end - 1]))) --end;
        const std::string image = line.substr(begin, end - begin);
        const glm::dvec3 d(xyz[0], xyz[1], xyz[2]);
        const double length = glm::length(d);
        if (!(length > 1e-6))
            fail(where(lineNumber), "image '" + image + "': light direction of zero length");
        if (d.z < 0)
            fail(where(lineNumber),
                 "image '" + image +
                     "': light direction below the horizon (z = " + f[f.size() - 1] + ")");
        const auto [previous, added] = seen.emplace(image, lineNumber);
        if (!added)
            fail(where(lineNumber), "image '" + image + "' is listed twice (also on line " +
                                        std::to_string(previous->second) + ")");
        lights.push_back({image, glm::vec3(d / length), lineNumber});
    }
    if (count < 0) fail(lpPath, "empty light-position file (expected the number of images)");
    if ((long long)lights.size() != count)
        fail(where(countLine), "says " + std::to_string(count) + " images, but " +
                                   std::to_string(lights.size()) + " are listed");
    return lights;
}

bool isRtiCapture(const std::string& path) {
    std::error_code ec;
    if (fs::is_regular_file(path, ec) && endsWithLp(path)) return true;
    try {
        if (!fs::is_directory(path, ec) && !(fs::is_regular_file(path, ec))) return false;
        ImageSetSource source(path);
        bool lp = false;
        for (const auto& entry : source.names()) {
            Ubo2003Name parsed;
            if (parseUbo2003Name(entry.first, parsed)) return false;
            lp |= endsWithLp(entry.first);
        }
        return lp;
    } catch (const Error&) {
        return false;
    }
}

namespace {

/** An RTI set's images, found: what both loadRti and openRtiCapture decode. */
struct RtiImages {
    std::unique_ptr<ImageSetSource> source;
    std::vector<ImageSetEntry> entries;
    DirectionSet views, lights;
    LoadOptions::DecodeCurve curve = LoadOptions::DecodeCurve::Srgb;
};

RtiImages findRtiImages(const std::string& path, const LoadOptions& options) {
    std::error_code ec;
    const bool lpGiven = fs::is_regular_file(path, ec) && endsWithLp(path);
    // The images come from the .lp file's folder (a given .lp), or from the folder or zip given.
    const std::string sourcePath = lpGiven ? fs::path(path).parent_path().empty()
                                                 ? std::string(".")
                                                 : fs::path(path).parent_path().string()
                                           : path;
    RtiImages found;
    found.source = std::make_unique<ImageSetSource>(sourcePath);
    const ImageSetSource& source = *found.source;
    std::string lpName;  // the .lp file's entry name in the source
    if (lpGiven) {
        lpName = fs::path(path).filename().string();
    } else {
        std::vector<std::string> found;
        for (const auto& entry : source.names())
            if (endsWithLp(entry.first)) found.push_back(entry.first);
        if (found.empty())
            fail(path, "no light-position file (.lp) found among " +
                           std::to_string(source.names().size()) + " entries");
        if (found.size() > 1)
            fail(path, "more than one light-position file: '" + found[0] + "' and '" + found[1] +
                           "' (name the one to use)");
        lpName = found.front();
    }
    ImageSetEntry lpEntry;
    lpEntry.name = lpName;
    bool lpListed = false;
    for (const auto& [name, zipIndex] : source.names())
        if (name == lpName) {
            lpEntry.zipIndex = zipIndex;
            lpListed = true;
        }
    if (!lpListed) fail(path, "cannot find '" + lpName + "'");
    // A light-position file of a million images is ~50 MB; more is not one.
    const std::vector<unsigned char> lpBytes = source.read(lpEntry, 64u << 20);
    const std::string lpLabel = lpGiven ? path : sourcePath + "/" + lpName;
    const std::vector<RtiLight> lights =
        parseLightPositions(std::string(lpBytes.begin(), lpBytes.end()), lpLabel);

    // Find each image: by its path relative to the .lp file's folder, else by file name alone.
    const std::string lpFolder = fs::path(lpName).parent_path().generic_string();
    std::map<std::string, std::pair<std::string, std::uint64_t>> byPath;
    std::map<std::string, std::vector<std::pair<std::string, std::uint64_t>>> byName;
    for (const auto& entry : source.names()) {
        byPath[entry.first] = entry;
        byName[imageSetBasename(entry.first)].push_back(entry);
    }
    std::vector<ImageSetEntry>& entries = found.entries;
    std::vector<Direction> directions;
    for (std::size_t i = 0; i < lights.size(); ++i) {
        const RtiLight& light = lights[i];
        const std::string relative = relativeName(light.image);
        const std::string inFolder = relative.empty()   ? ""
                                     : lpFolder.empty() ? relative
                                                        : lpFolder + "/" + relative;
        const std::pair<std::string, std::uint64_t>* match = nullptr;
        if (!inFolder.empty() && byPath.count(inFolder)) {
            match = &byPath[inFolder];
        } else {
            const auto named = byName.find(imageSetBasename(light.image));
            if (named != byName.end() && named->second.size() > 1)
                fail(lpLabel + ":" + std::to_string(light.line),
                     "image '" + light.image + "' is ambiguous: '" + named->second[0].first +
                         "' and '" + named->second[1].first + "'");
            if (named != byName.end()) match = &named->second.front();
        }
        if (!match)
            fail(lpLabel + ":" + std::to_string(light.line),
                 "image '" + light.image + "' not found in " + sourcePath);
        ImageSetEntry entry;
        entry.name = match->first;
        entry.zipIndex = match->second;
        entry.extension = extensionOf(match->first);
        entry.view = 0;
        entry.light = int(i);
        entries.push_back(entry);
        directions.push_back(Direction::fromVector(light.direction));
    }
    found.views = DirectionSet("rti-view", {{0, 0}});
    found.lights = DirectionSet("rti-lights", std::move(directions));
    // Camera photos are sRGB-encoded unless the caller says otherwise.
    found.curve = options.curve == LoadOptions::DecodeCurve::Auto ? LoadOptions::DecodeCurve::Srgb
                                                                  : options.curve;
    return found;
}

}  // namespace

MeasuredBtf loadRti(const std::string& path, const LoadOptions& options) {
    const RtiImages found = findRtiImages(path, options);
    MeasuredBtf btf = decodeImageSet(*found.source, found.entries, found.views, found.lights,
                                     options, found.curve);
    btf.source = path;
    return btf;
}

RtiCaptureHeader readRtiCaptureHeader(const std::string& path, const LoadOptions& options) {
    const RtiImages found = findRtiImages(path, options);
    const ImageSetHeader first = readImageSetHeader(*found.source, found.entries.front());
    RtiCaptureHeader header;
    header.width = first.width;
    header.height = first.height;
    header.rawBytes = first.rawBytes;
    header.lights = found.lights;
    header.decoding = decodeCurveLabel(found.curve);
    return header;
}

bool rtiCaptureOnDisk(int width, int height, std::size_t lights, const LoadOptions& options) {
    switch (options.placement) {
        case LoadOptions::Placement::Disk:
            return true;
        case LoadOptions::Placement::Memory:
            return false;
        case LoadOptions::Placement::Auto:
            break;
    }
    // A quarter: the fits hold their model and working blocks beside the measured values.
    return MeasuredBtf::bytesNeeded(width, height, 1, lights, options.storage) > memoryLimit() / 4;
}

std::unique_ptr<BtfSource> openRtiCapture(const std::string& path, const LoadOptions& options) {
    const RtiImages found = findRtiImages(path, options);
    const ImageSetHeader first = readImageSetHeader(*found.source, found.entries.front());
    if (!rtiCaptureOnDisk(first.width, first.height, found.lights.size(), options)) {
        // Kept in memory (told to, or small enough): over the limit, say the way out that needs
        // no more memory, before a photo is decoded.
        const std::uint64_t bytes = MeasuredBtf::bytesNeeded(first.width, first.height, 1,
                                                             found.lights.size(), options.storage);
        if (bytes > memoryLimit())
            throw Error(path + ": an RTI capture of " + std::to_string(first.width) + "x" +
                        std::to_string(first.height) + " pixels x " +
                        std::to_string(found.lights.size()) + " photos: needs " +
                        formatBytes(bytes) + " in memory, more than the memory limit of " +
                        formatBytes(memoryLimit()) +
                        " (keep it on disk with --storage disk, or raise the limit with "
                        "--memory-limit or OSGBTF_MEMORY_LIMIT)");
        auto btf = std::make_unique<MeasuredBtf>(decodeImageSet(
            *found.source, found.entries, found.views, found.lights, options, found.curve));
        btf->source = path;
        return btf;
    }
    const std::string label =
        options.progressLabel.empty()
            ? "decoding " + std::to_string(found.entries.size()) + " photos to " + outOfCoreFolder()
            : options.progressLabel;
    auto btf = std::make_unique<OutOfCoreImageSet>(*found.source, found.entries, found.views,
                                                   found.lights, found.curve, label);
    btf->source = path;
    return btf;
}

}  // namespace osgBTF

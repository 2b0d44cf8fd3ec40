#include "loaders/LoadBtf.h"

#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/Error.h"
#include "loaders/Rti.h"
#include "loaders/Ubo2003.h"
#include "loaders/Ubo2014.h"

namespace osgBTF {

namespace {
std::string dottedLowerExtension(const std::string& path) {
    std::string extension = std::filesystem::path(path).extension().string();
    for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
    return extension;
}
}  // namespace

bool isUbo2014File(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return false;
    const std::string extension = dottedLowerExtension(path);
    if (extension == ".btf") return true;
    if (extension == ".zip") return false;
    std::ifstream in(path, std::ios::binary);
    char first = 0;
    return in.get(first) && first == '!';
}

MeasuredBtf loadMeasuredBtf(const std::string& path, const LoadOptions& options) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (status.type() == fs::file_type::not_found) fail(path, "no such file");
    if (ec) fail(path, "cannot open: " + ec.message());
    const std::string extension = dottedLowerExtension(path);

    MeasuredBtf btf;
    if (isRtiCapture(path)) {
        btf = loadRti(path, options);
    } else if (status.type() == fs::file_type::directory) {
        // A folder named like a file is almost certainly a mistake, not a folder of images.
        if (extension == ".btf" || extension == ".zip")
            fail(path, "cannot open: " + std::string(std::strerror(EISDIR)));
        btf = loadUbo2003(path, options);
    } else {
        std::ifstream in(path, std::ios::binary);
        if (!in) fail(path, "cannot open: " + std::string(std::strerror(errno)));
        char magic[4] = {};
        in.read(magic, 4);
        const std::streamsize got = in.gcount();
        if (got == 0) fail(path, "file is empty");
        in.close();
        const bool zipMagic = got == 4 && std::memcmp(magic, "PK\x03\x04", 4) == 0;
        if (extension == ".zip" || (extension != ".btf" && zipMagic))
            btf = loadUbo2003(path, options);
        else if (extension == ".btf" || magic[0] == '!')
            btf = loadUbo2014(path, options);
        else
            fail(path,
                 "unknown file type (expected a UBO2003 .zip, a UBO2014 .btf, a folder "
                 "of UBO2003 images or an RTI set: a .lp file, or a folder or zip with one)");
    }
    btf.source = path;
    return btf;
}

std::unique_ptr<BtfSource> openBtfSource(const std::string& path, const LoadOptions& options) {
    if (isUbo2014File(path)) {
        auto factors = std::make_shared<Ubo2014Factors>(readUbo2014(path, options));
        factors->source = path;
        return std::make_unique<FactoredBtfSource>(
            std::shared_ptr<const FactoredBtf>(std::move(factors)));
    }
    if (isRtiCapture(path)) return openRtiCapture(path, options);
    return std::make_unique<MeasuredBtf>(loadMeasuredBtf(path, options));
}

}  // namespace osgBTF

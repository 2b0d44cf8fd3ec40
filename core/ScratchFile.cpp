#include "core/ScratchFile.h"

#include <fcntl.h>
#include <unistd.h>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "core/Error.h"
#include "core/MeasuredBtf.h"

namespace osgBTF {

namespace fs = std::filesystem;

std::string scratchFolder() {
    for (const char* variable : {"OSGBTF_CACHE_DIR", "TMPDIR"})
        if (const char* value = std::getenv(variable); value && *value) return value;
    return "/tmp";
}

namespace {

/** An unnamed file in `folder`: nothing is left behind when the process ends, killed or not. */
int openUnnamedFile(const std::string& folder) {
#ifdef O_TMPFILE
    const int fd = ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd >= 0) return fd;
#endif
    // File systems without O_TMPFILE: a named file, unlinked at once.
    std::string name = (fs::path(folder) / "osgbtf-scratch-XXXXXX").string();
    const int named = ::mkstemp(name.data());
    if (named < 0)
        fail(folder, std::string("cannot create a temporary file: ") + std::strerror(errno));
    ::unlink(name.c_str());
    return named;
}

}  // namespace

ScratchFile::ScratchFile(std::uint64_t bytes, std::string owner, std::string contents)
    : _folder(scratchFolder()), _owner(std::move(owner)), _contents(std::move(contents)) {
    std::error_code ec;
    const fs::space_info space = fs::space(_folder, ec);
    if (ec)
        fail(_folder, "cannot use it for the " + _contents + " of " + _owner + ": " + ec.message());
    if (space.available < bytes + (std::uint64_t(256) << 20))
        fail(_owner, "needs " + formatBytes(bytes) + " of disk for its " + _contents + " in " +
                         _folder + ", " + formatBytes(space.available) +
                         " free there (set OSGBTF_CACHE_DIR or TMPDIR to a folder with room)");
    _fd = openUnnamedFile(_folder);
    // Allocated up front: running out of disk fails here, not half-way through the writing.
    if (const int error = ::posix_fallocate(_fd, 0, off_t(bytes));
        error != 0 && error != EOPNOTSUPP) {
        ::close(_fd);
        _fd = -1;
        fail(_owner, "cannot reserve " + formatBytes(bytes) + " in " + _folder + ": " +
                         std::strerror(error));
    }
}

ScratchFile::~ScratchFile() {
    if (_fd >= 0) ::close(_fd);
}

void ScratchFile::read(void* to, std::uint64_t bytes, std::uint64_t offset) const {
    auto* at = static_cast<unsigned char*>(to);
    while (bytes > 0) {
        const ssize_t n = ::pread(_fd, at, bytes, off_t(offset));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            fail(_owner, "cannot read the " + _contents + " back from " + _folder + ": " +
                             (n < 0 ? std::strerror(errno) : "unexpected end of file"));
        at += n;
        bytes -= std::uint64_t(n);
        offset += std::uint64_t(n);
    }
}

void ScratchFile::write(const void* from, std::uint64_t bytes, std::uint64_t offset) {
    const auto* at = static_cast<const unsigned char*>(from);
    while (bytes > 0) {
        const ssize_t n = ::pwrite(_fd, at, bytes, off_t(offset));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            fail(_owner,
                 "cannot write its " + _contents + " to " + _folder + ": " + std::strerror(errno));
        at += n;
        bytes -= std::uint64_t(n);
        offset += std::uint64_t(n);
    }
}

}  // namespace osgBTF

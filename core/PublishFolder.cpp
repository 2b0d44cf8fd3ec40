#include "core/PublishFolder.h"

#include <fcntl.h>  // AT_FDCWD
#include <unistd.h>

#include <cstdio>  // renameat2, RENAME_EXCHANGE (glibc, _GNU_SOURCE)
#include <filesystem>

#include "core/Error.h"

namespace osgBTF {

namespace fs = std::filesystem;

void publishFolder(const std::string& temporaryName, const std::string& targetName) {
    const fs::path temporary(temporaryName), target(targetName);
    std::error_code ec;
    fs::path old;
    // Swapping the two names in one step leaves no moment without `target` for a reader (or a
    // kill) to find; the previous results then sit under the temporary name until removed.
    if (fs::exists(target) &&
        ::renameat2(AT_FDCWD, temporary.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) == 0) {
        fs::remove_all(temporary, ec);
        return;
    }
    // A file system without RENAME_EXCHANGE: move the old folder aside first.
    if (fs::exists(target)) {
        old = target;
        old += ".old" + std::to_string(getpid());
        fs::rename(target, old, ec);
        if (ec) throw Error(target.string() + ": cannot replace: " + ec.message());
    }
    fs::rename(temporary, target, ec);
    if (ec) {
        if (!old.empty()) fs::rename(old, target);
        throw Error(target.string() + ": cannot rename " + temporary.string() +
                    " to it: " + ec.message());
    }
    if (!old.empty()) fs::remove_all(old, ec);
}

}  // namespace osgBTF

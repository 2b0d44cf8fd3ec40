// osgBTF: an unnamed file on disk for data that does not fit in memory (a capture's decoded photos,
// a mip-map atlas's coarse levels). Its room is checked and reserved before anything is written,
// and nothing is left behind when it is closed or the process ends, killed or not.
#pragma once

#include <cstdint>
#include <string>

namespace osgBTF {

/** Where scratch files go: $OSGBTF_CACHE_DIR, else $TMPDIR, else /tmp. */
std::string scratchFolder();

class ScratchFile {
public:
    /** Creates the file in scratchFolder() with `bytes` reserved. `owner` (a file name) and
     *  `contents` ("decoded photos") make the messages: Error "OWNER: needs 3.4 GiB of disk
     *  for its CONTENTS in DIR, 1.2 GiB free there (set OSGBTF_CACHE_DIR or TMPDIR to a folder with
     *  room)", "OWNER: cannot reserve ...". */
    ScratchFile(std::uint64_t bytes, std::string owner, std::string contents);
    ~ScratchFile();
    ScratchFile(const ScratchFile&) = delete;
    ScratchFile& operator=(const ScratchFile&) = delete;

    /** Thread-safe (pread). Error "OWNER: cannot read the CONTENTS back from DIR: why". */
    void read(void* to, std::uint64_t bytes, std::uint64_t offset) const;
    /** Thread-safe for disjoint ranges (pwrite). Error "OWNER: cannot write its CONTENTS to DIR:
     *  why". */
    void write(const void* from, std::uint64_t bytes, std::uint64_t offset);
    const std::string& folder() const { return _folder; }

private:
    int _fd = -1;
    std::string _folder, _owner, _contents;
};

}  // namespace osgBTF

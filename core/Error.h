// osgBTF: errors and small diagnostics shared by every unit.
#pragma once

#include <stdexcept>
#include <string>

namespace osgBTF {

/** Every failure osgBTF reports to its user. The message names the file (when there is one) and
 *  the problem, e.g. "x.zip: member 'tl000 pl000 tv000 pv000.jpg' is missing". Tools print it and
 *  exit non-zero; osgDB plugins turn it into ReadResult::ERROR_IN_READING_FILE. */
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/** "file: problem", the one format of every message that concerns a file. */
[[noreturn]] void fail(const std::string& file, const std::string& problem);

}  // namespace osgBTF

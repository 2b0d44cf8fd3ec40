// osgBTF: publishing a folder of results so that a reader (or a kill) never finds half of it.
#pragma once

#include <string>

namespace osgBTF {

/** Replaces `target` by the finished folder `temporary` (both in the same parent; name the
 *  temporary "<target>.tmp<pid>" so removeStaleTemporaries cleans what a killed writer left).
 *  Swaps the two names in one step where the file system can (RENAME_EXCHANGE), else moves an
 *  existing `target` aside to "<target>.old<pid>" first and back on failure. Throws Error
 *  "TARGET: cannot ..." naming the problem. */
void publishFolder(const std::string& temporary, const std::string& target);

}  // namespace osgBTF

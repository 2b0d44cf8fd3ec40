#include "core/Notify.h"

#include <mutex>

namespace osgBTF {

void notifyLine(osg::NotifySeverity level, const std::string& line) {
    static std::mutex mutex;
    const std::lock_guard<std::mutex> lock(mutex);
    osg::notify(level) << line << std::endl;
}

}  // namespace osgBTF

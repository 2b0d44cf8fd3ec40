// osg::notify writes into one stream for the whole process, which is not thread-safe: loader
// threads (osgDB's DatabasePager, an application's own) and cull threads logging at once race on
// its buffer (ThreadSanitizer found it, README "Reliability"). osgBTF's messages are formatted
// first and written whole under one lock.
#pragma once

#include <sstream>
#include <string>

#include <osg/Notify>

namespace osgBTF {

/** Writes `line` and std::endl to osg::notify(level) under a process-wide lock. */
void notifyLine(osg::NotifySeverity level, const std::string& line);

}  // namespace osgBTF

/** OSGBTF_NOTIFY(osg::NOTICE, "a " << b) instead of OSG_NOTICE << "a " << b << std::endl. */
#define OSGBTF_NOTIFY(level, message)                            \
    do {                                                         \
        if (osg::isNotifyEnabled(level)) {                       \
            std::ostringstream osgbtfNotifyText;                 \
            osgbtfNotifyText << message;                         \
            ::osgBTF::notifyLine(level, osgbtfNotifyText.str()); \
        }                                                        \
    } while (false)

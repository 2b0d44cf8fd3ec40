// osgBTF GL tests: OSG's GL error check on every attribute of the shared renderer's context, and
// the errors it reports collected (tests/gl/gl_errors_test.cpp, paged_scene_test.cpp).
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

#include <osg/GraphicsContext>
#include <osg/Notify>
#include <osg/State>

#include "tests/NotifyCapture.h"
#include "tests/gl/GlTestEnv.h"

namespace osgBTF::test {

inline osg::State& sharedState() {
    osg::GraphicsContext* context = sharedRenderer().camera().getGraphicsContext();
    if (!context || !context->getState())
        throw std::runtime_error("the shared context has no State");
    return *context->getState();
}

/** While alive: OSG checks for a GL error after every attribute, and its reports are collected.
 *  Some of them are notices (osg::State::checkGLErrors), so notices are let through. */
class GlErrorWatch {
public:
    GlErrorWatch() : _check(sharedState().getCheckForGLErrors()), _level(osg::getNotifyLevel()) {
        sharedState().setCheckForGLErrors(osg::State::ONCE_PER_ATTRIBUTE);
        if (_level < osg::NOTICE) osg::setNotifyLevel(osg::NOTICE);
    }
    ~GlErrorWatch() {
        sharedState().setCheckForGLErrors(_check);
        osg::setNotifyLevel(_level);
    }
    /** The lines that reported a GL error since the last call. */
    std::string take() {
        std::istringstream lines(_capture.text());
        std::string line, errors;
        while (std::getline(lines, line))
            if (line.find("OpenGL error") != std::string::npos) errors += line + "\n";
        _capture.capture->text.clear();
        return errors;
    }

private:
    osg::State::CheckForGLErrors _check;
    osg::NotifySeverity _level;
    ScopedNotifyCapture _capture{true};  // echoed: the driver's own messages help on a failure
};

}  // namespace osgBTF::test

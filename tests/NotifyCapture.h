// osgBTF tests: collects OSG notifications (OSG_WARN etc.) so tests can assert on the messages.
#pragma once

#include <cstdio>
#include <string>

#include <osg/Notify>

namespace osgBTF::test {

class NotifyCapture : public osg::NotifyHandler {
public:
    explicit NotifyCapture(bool echo) : _echo(echo) {}
    void notify(osg::NotifySeverity, const char* message) override {
        text += message;
        if (_echo) std::fputs(message, stderr);
    }
    std::string text;

private:
    bool _echo;
};

/** Captures while alive, then restores OSG's standard handler. `echo` also prints the messages
 *  (useful in GL tests, whose driver messages help when a test fails). */
struct ScopedNotifyCapture {
    explicit ScopedNotifyCapture(bool echo = false) : capture(new NotifyCapture(echo)) {
        osg::setNotifyHandler(capture.get());
    }
    ~ScopedNotifyCapture() { osg::setNotifyHandler(new osg::StandardNotifyHandler); }
    const std::string& text() const { return capture->text; }
    osg::ref_ptr<NotifyCapture> capture;
};

}  // namespace osgBTF::test

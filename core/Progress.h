// osgBTF: a progress bar on stderr for long work (loading, fitting).
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <functional>
#include <mutex>
#include <string>

#include "core/Error.h"

namespace osgBTF {

/** Thread-safe: advance() may be called from TBB workers. Draws at most ~10 times a second, only
 *  when enabled (the tools enable it when stderr is a terminal or --progress is given; tests and
 *  libraries leave it off so their output stays clean). */
class Progress {
public:
    /** Thrown by advance() once a stop was requested (requestStop, or an observer that returned
     *  false): the long work unwinds with it, like with any other Error. */
    class Cancelled : public Error {
    public:
        Cancelled() : Error("cancelled") {}
    };

    Progress(std::string label, std::size_t total);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    void advance(std::size_t n = 1);
    /** Prints the final line with the elapsed time. Called by the destructor if not before. */
    void finish();
    double elapsedSeconds() const;

    static void setEnabled(bool enabled);
    static bool enabled();

    /** Hears every Progress of the process (label, done, total), from the thread that calls
     *  advance() (any thread: the observer must be thread-safe), at most ~10 times a second per
     *  Progress and once from finish(). Returning false asks the work to stop (requestStop).
     *  Empty: none. A program that embeds osgBTF (the Python module) reports and cancels fits
     *  through it. */
    using Observer =
        std::function<bool(const std::string& label, std::size_t done, std::size_t total)>;
    static void setObserver(Observer observer);
    /** From any thread or a signal handler: every later advance() of every Progress throws
     *  Cancelled, until clearStop(). */
    static void requestStop();
    static bool stopRequested();
    static void clearStop();

private:
    void draw(bool final);
    void notify(std::size_t done);

    std::string _label;
    std::size_t _total;
    std::atomic<std::size_t> _done{0};
    std::chrono::steady_clock::time_point _start, _lastDraw;
    std::mutex _drawMutex;
    bool _finished = false;
};

}  // namespace osgBTF

// osgBTF: a progress bar on stderr for long work (loading, fitting).
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <mutex>
#include <string>

namespace osgBTF {

/** Thread-safe: advance() may be called from TBB workers. Draws at most ~10 times a second, only
 *  when enabled (the tools enable it when stderr is a terminal or --progress is given; tests and
 *  libraries leave it off so their output stays clean). */
class Progress {
public:
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

private:
    void draw(bool final);

    std::string _label;
    std::size_t _total;
    std::atomic<std::size_t> _done{0};
    std::chrono::steady_clock::time_point _start, _lastDraw;
    std::mutex _drawMutex;
    bool _finished = false;
};

}  // namespace osgBTF

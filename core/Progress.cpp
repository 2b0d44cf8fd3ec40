#include "core/Progress.h"

#include <cstdio>

namespace osgBTF {

namespace {
std::atomic<bool> g_enabled{false};
}

void Progress::setEnabled(bool enabled) {
    g_enabled = enabled;
}
bool Progress::enabled() {
    return g_enabled;
}

Progress::Progress(std::string label, std::size_t total)
    : _label(std::move(label)), _total(total), _start(std::chrono::steady_clock::now()) {}

Progress::~Progress() {
    finish();
}

double Progress::elapsedSeconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - _start).count();
}

void Progress::advance(std::size_t n) {
    _done += n;
    if (!g_enabled) return;
    const auto now = std::chrono::steady_clock::now();
    std::unique_lock<std::mutex> lock(_drawMutex, std::try_to_lock);
    if (!lock.owns_lock() || now - _lastDraw < std::chrono::milliseconds(100)) return;
    _lastDraw = now;
    draw(false);
}

void Progress::finish() {
    std::lock_guard<std::mutex> lock(_drawMutex);
    if (_finished) return;
    _finished = true;
    if (g_enabled) draw(true);
}

void Progress::draw(bool final) {
    const std::size_t done = final ? _total : std::min<std::size_t>(_done.load(), _total);
    const double fraction = _total ? double(done) / double(_total) : 1.0;
    const int width = 30;
    const int filled = int(fraction * width + 0.5);
    std::string bar(std::size_t(filled), '#');
    bar.append(std::size_t(width - filled), '.');
    const double elapsed = elapsedSeconds();
    if (final) {
        std::fprintf(stderr, "\r%s [%s] %zu/%zu  %.1f s\n", _label.c_str(), bar.c_str(), done,
                     _total, elapsed);
    } else {
        const double eta = fraction > 0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
        std::fprintf(stderr, "\r%s [%s] %zu/%zu  %.1f s, ~%.0f s left ", _label.c_str(),
                     bar.c_str(), done, _total, elapsed, eta);
    }
    std::fflush(stderr);
}

}  // namespace osgBTF

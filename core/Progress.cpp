#include "core/Progress.h"

#include <algorithm>
#include <cstdio>
#include <memory>

namespace osgBTF {

namespace {
std::atomic<bool> g_enabled{false};
std::atomic<bool> g_stop{false};
// Set rarely (a program installs one observer); read under the mutex as a shared copy, so that
// an observer replaced while a worker calls it stays alive until that call returns.
std::mutex g_observerMutex;
std::shared_ptr<const Progress::Observer> g_observer;
std::atomic<bool> g_hasObserver{false};

std::shared_ptr<const Progress::Observer> currentObserver() {
    if (!g_hasObserver.load(std::memory_order_relaxed)) return nullptr;
    std::lock_guard<std::mutex> lock(g_observerMutex);
    return g_observer;
}
}  // namespace

void Progress::setObserver(Observer observer) {
    std::lock_guard<std::mutex> lock(g_observerMutex);
    g_observer = observer ? std::make_shared<const Observer>(std::move(observer)) : nullptr;
    g_hasObserver = g_observer != nullptr;
}
void Progress::requestStop() {
    g_stop = true;
}
bool Progress::stopRequested() {
    return g_stop;
}
void Progress::clearStop() {
    g_stop = false;
}

void Progress::notify(std::size_t done) {
    if (const auto observer = currentObserver())
        if (!(*observer)(_label, std::min(done, _total), _total)) g_stop = true;
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
    const std::size_t done = _done += n;
    if (g_stop.load(std::memory_order_relaxed)) throw Cancelled();
    if (!g_enabled && !g_hasObserver.load(std::memory_order_relaxed)) return;
    const auto now = std::chrono::steady_clock::now();
    std::unique_lock<std::mutex> lock(_drawMutex, std::try_to_lock);
    if (!lock.owns_lock() || now - _lastDraw < std::chrono::milliseconds(100)) return;
    _lastDraw = now;
    if (g_enabled) draw(false);
    notify(done);
    if (g_stop.load(std::memory_order_relaxed)) throw Cancelled();
}

void Progress::finish() {
    std::lock_guard<std::mutex> lock(_drawMutex);
    if (_finished) return;
    _finished = true;
    if (g_enabled) draw(true);
    // Told the total, never asked to stop: finish() also runs from the destructor.
    if (g_stop) return;
    try {
        if (const auto observer = currentObserver()) (*observer)(_label, _total, _total);
    } catch (...) {
    }
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

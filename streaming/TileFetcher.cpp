#include "streaming/TileFetcher.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <new>

#include <curl/curl.h>

#include "core/Notify.h"

namespace osgBTF {

FetchResult TileSource::fetchInterruptible(const std::string& relativePath,
                                           const std::atomic<bool>&) {
    return fetch(relativePath);
}

namespace {

FetchResult failure(const std::string& where, const std::string& problem) {
    FetchResult result;
    result.error = where + ": " + problem;
    return result;
}

std::string errnoText(int error) {
    return std::strerror(error);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// FolderTileSource

FolderTileSource::FolderTileSource(std::string folder) : _folder(std::move(folder)) {}

std::string FolderTileSource::describe(const std::string& relativePath) const {
    if (_folder.empty()) return relativePath;
    return (std::filesystem::path(_folder) / relativePath).string();
}

FetchResult FolderTileSource::fetch(const std::string& relativePath) {
    const std::string path = describe(relativePath);
    // POSIX rather than ifstream: errno names the problem, and a folder is refused at open.
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return failure(path, "cannot open: " + errnoText(errno));
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    struct stat info {};
    if (::fstat(fd, &info) != 0) return failure(path, "cannot open: " + errnoText(errno));
    if (S_ISDIR(info.st_mode)) return failure(path, "cannot open: " + errnoText(EISDIR));
    if (!S_ISREG(info.st_mode)) return failure(path, "cannot open: not a regular file");

    FetchResult result;
    try {
        result.data.reserve(std::size_t(info.st_size));
        std::uint8_t buffer[65536];
        for (;;) {
            const ssize_t n = ::read(fd, buffer, sizeof buffer);
            if (n < 0) {
                if (errno == EINTR) continue;
                return failure(path, "cannot read: " + errnoText(errno));
            }
            if (n == 0) break;
            result.data.insert(result.data.end(), buffer, buffer + n);
        }
    } catch (const std::bad_alloc&) {
        return failure(path, "cannot read: out of memory");
    }
    result.ok = true;
    return result;
}

// ---------------------------------------------------------------------------------------------
// HttpTileSource

namespace {

constexpr long kMaxRedirects = 3;

/** Whether a failed transfer may succeed when tried again: the connection (refused, reset,
 *  stalled, cut short) or the server's state (5xx, 408 Request Timeout, 429 Too Many Requests),
 *  not an answer about the file (404, redirect loops) or a limit of ours (size, cancelled). */
bool isTransient(CURLcode code, long status) {
    switch (code) {
        case CURLE_OK:
        case CURLE_HTTP_RETURNED_ERROR:
            return status >= 500 || status == 408 || status == 429;
        case CURLE_COULDNT_CONNECT:
        case CURLE_COULDNT_RESOLVE_HOST:
        case CURLE_COULDNT_RESOLVE_PROXY:
        case CURLE_OPERATION_TIMEDOUT:
        case CURLE_GOT_NOTHING:
        case CURLE_PARTIAL_FILE:
        case CURLE_SEND_ERROR:
        case CURLE_RECV_ERROR:
            return true;
        default:
            return false;
    }
}

/** curl_global_init is not thread-safe before libcurl 7.84; once per process, never cleaned up
 *  (other libraries in the process may use libcurl too). */
bool curlReady() {
    static std::once_flag once;
    static bool ready = false;
    std::call_once(once, [] { ready = curl_global_init(CURL_GLOBAL_DEFAULT) == CURLE_OK; });
    return ready;
}

/** One easy handle per thread: a handle must not be used by two threads at once, and reusing it
 *  keeps the connection to the server alive between tiles. */
CURL* threadHandle() {
    struct Handle {
        CURL* curl = nullptr;
        ~Handle() {
            if (curl) curl_easy_cleanup(curl);
        }
    };
    thread_local Handle handle;
    if (handle.curl)
        curl_easy_reset(handle.curl);  // options back to defaults; connections stay cached
    else
        handle.curl = curl_easy_init();
    return handle.curl;
}

struct Transfer {
    std::vector<std::uint8_t> data;
    std::size_t maxBytes = 0;
    bool tooLarge = false;
    bool outOfMemory = false;
    const std::atomic<bool>* stop = nullptr;
};

extern "C" size_t writeBody(char* bytes, size_t size, size_t count, void* user) {
    auto* transfer = static_cast<Transfer*>(user);
    const std::size_t n = size * count;
    if (n > transfer->maxBytes - transfer->data.size()) {
        transfer->tooLarge = true;
        return 0;  // != n: libcurl aborts with CURLE_WRITE_ERROR
    }
    try {
        transfer->data.insert(transfer->data.end(), reinterpret_cast<std::uint8_t*>(bytes),
                              reinterpret_cast<std::uint8_t*>(bytes) + n);
    } catch (const std::bad_alloc&) {
        transfer->outOfMemory = true;
        return 0;
    }
    return n;
}

extern "C" int transferProgress(void* user, curl_off_t, curl_off_t, curl_off_t, curl_off_t) {
    const auto* transfer = static_cast<const Transfer*>(user);
    return transfer->stop && transfer->stop->load() ? 1 : 0;  // non-zero aborts the transfer
}

bool unreserved(unsigned char c) {
    return std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~' || c == '/';
}

std::string percentEncode(const std::string& text) {
    static const char* const hex = "0123456789ABCDEF";
    std::string out;
    for (unsigned char c : text) {
        if (unreserved(c)) {
            out += char(c);
        } else {
            out += '%';
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    return out;
}

bool startsWithNoCase(const std::string& text, const std::string& prefix) {
    if (text.size() < prefix.size()) return false;
    for (std::size_t i = 0; i < prefix.size(); ++i)
        if (std::tolower(static_cast<unsigned char>(text[i])) != prefix[i]) return false;
    return true;
}

}  // namespace

HttpTileSource::HttpTileSource(std::string baseUrl, HttpOptions options)
    : _baseUrl(std::move(baseUrl)), _options(options) {
    while (!_baseUrl.empty() && _baseUrl.back() == '/') _baseUrl.pop_back();
    _options.connectTimeoutSeconds = std::max(1L, _options.connectTimeoutSeconds);
    _options.stallSeconds = std::max(1L, _options.stallSeconds);
}

std::string HttpTileSource::describe(const std::string& relativePath) const {
    std::size_t start = 0;
    while (start < relativePath.size() && relativePath[start] == '/') ++start;
    return _baseUrl + "/" + percentEncode(relativePath.substr(start));
}

FetchResult HttpTileSource::fetch(const std::string& relativePath) {
    static const std::atomic<bool> never{false};
    return fetchInterruptible(relativePath, never);
}

FetchResult HttpTileSource::fetchInterruptible(const std::string& relativePath,
                                               const std::atomic<bool>& stop) {
    const std::string url = describe(relativePath);
    if (!curlReady()) return failure(url, "cannot initialise libcurl");
    CURL* curl = threadHandle();
    if (!curl) return failure(url, "cannot create a libcurl handle");

    Transfer transfer;
    transfer.maxBytes = _options.maxBytes;
    transfer.stop = &stop;
    char errorBuffer[CURL_ERROR_SIZE] = {};

    curl_easy_setopt(curl, CURLOPT_URL, url.c_str());
    curl_easy_setopt(curl, CURLOPT_ERRORBUFFER, errorBuffer);
    curl_easy_setopt(curl, CURLOPT_NOSIGNAL, 1L);  // threads: no SIGALRM for timeouts
#if LIBCURL_VERSION_NUM >= 0x075500
    curl_easy_setopt(curl, CURLOPT_PROTOCOLS_STR, "http,https");
    curl_easy_setopt(curl, CURLOPT_REDIR_PROTOCOLS_STR, "http,https");
#else
    curl_easy_setopt(curl, CURLOPT_PROTOCOLS, long(CURLPROTO_HTTP | CURLPROTO_HTTPS));
    curl_easy_setopt(curl, CURLOPT_REDIR_PROTOCOLS, long(CURLPROTO_HTTP | CURLPROTO_HTTPS));
#endif
    curl_easy_setopt(curl, CURLOPT_FOLLOWLOCATION, 1L);
    curl_easy_setopt(curl, CURLOPT_MAXREDIRS, kMaxRedirects);
    curl_easy_setopt(curl, CURLOPT_FAILONERROR, 1L);  // no error page bodies
    curl_easy_setopt(curl, CURLOPT_CONNECTTIMEOUT, _options.connectTimeoutSeconds);
    curl_easy_setopt(curl, CURLOPT_LOW_SPEED_LIMIT, 1L);
    curl_easy_setopt(curl, CURLOPT_LOW_SPEED_TIME, _options.stallSeconds);
    if (_options.maxBytes <= std::size_t(std::numeric_limits<curl_off_t>::max()))
        curl_easy_setopt(curl, CURLOPT_MAXFILESIZE_LARGE, curl_off_t(_options.maxBytes));
    curl_easy_setopt(curl, CURLOPT_USERAGENT, "osgBTF");
    curl_easy_setopt(curl, CURLOPT_WRITEFUNCTION, writeBody);
    curl_easy_setopt(curl, CURLOPT_WRITEDATA, &transfer);
    curl_easy_setopt(curl, CURLOPT_XFERINFOFUNCTION, transferProgress);
    curl_easy_setopt(curl, CURLOPT_XFERINFODATA, &transfer);
    curl_easy_setopt(curl, CURLOPT_NOPROGRESS, 0L);

    const CURLcode code = curl_easy_perform(curl);
    long status = 0;
    curl_easy_getinfo(curl, CURLINFO_RESPONSE_CODE, &status);
    long osErrno = 0;
    curl_easy_getinfo(curl, CURLINFO_OS_ERRNO, &osErrno);
    curl_off_t connectMicroseconds = 0;
    curl_easy_getinfo(curl, CURLINFO_CONNECT_TIME_T, &connectMicroseconds);
    curl_easy_setopt(curl, CURLOPT_ERRORBUFFER, nullptr);  // errorBuffer dies with this frame

    const bool transient = isTransient(code, status);
    const auto fail = [&](const std::string& problem) {
        FetchResult result = failure(url, problem);
        result.transient = transient;
        return result;
    };
    const std::string sizeLimit =
        "response larger than " + std::to_string(_options.maxBytes) + " bytes";
    switch (code) {
        case CURLE_OK:
            if (status < 200 || status > 299) return fail("HTTP " + std::to_string(status));
            break;
        case CURLE_ABORTED_BY_CALLBACK:
            return fail("cancelled");
        case CURLE_HTTP_RETURNED_ERROR:
            return fail("HTTP " + std::to_string(status));
        case CURLE_FILESIZE_EXCEEDED:
            return fail(sizeLimit);
        case CURLE_WRITE_ERROR:
            if (transfer.tooLarge) return fail(sizeLimit);
            if (transfer.outOfMemory) return fail("out of memory");
            break;
        case CURLE_COULDNT_CONNECT:
            if (osErrno == ECONNREFUSED) return fail("connection refused");
            if (osErrno != 0) return fail("cannot connect: " + errnoText(int(osErrno)));
            break;
        case CURLE_OPERATION_TIMEDOUT:
            if (connectMicroseconds > 0)
                return fail("timed out (no data for " + std::to_string(_options.stallSeconds) +
                            " s)");
            return fail("cannot connect: timed out after " +
                        std::to_string(_options.connectTimeoutSeconds) + " s");
        case CURLE_TOO_MANY_REDIRECTS:
            return fail("more than " + std::to_string(kMaxRedirects) + " redirects");
        case CURLE_GOT_NOTHING:
            return fail("empty reply from the server");
        case CURLE_PARTIAL_FILE:
            return fail("the connection closed before the whole response arrived");
        default:
            break;
    }
    if (code != CURLE_OK)
        return fail(errorBuffer[0] ? std::string(errorBuffer) : curl_easy_strerror(code));

    FetchResult result;
    result.ok = true;
    result.data = std::move(transfer.data);
    return result;
}

std::unique_ptr<TileSource> openTileSource(const std::string& location) {
    if (startsWithNoCase(location, "http://") || startsWithNoCase(location, "https://"))
        return std::make_unique<HttpTileSource>(location);
    return std::make_unique<FolderTileSource>(location);
}

// ---------------------------------------------------------------------------------------------
// TileFetcher

bool TileFetcher::QueueEntry::operator<(const QueueEntry& other) const {
    if (priority != other.priority) return priority > other.priority;
    return sequence < other.sequence;
}

TileFetcher::TileFetcher(std::shared_ptr<TileSource> source, TileFetcherOptions options)
    : _source(std::move(source)), _options(options), _paused(options.paused) {
    _options.tries = std::max(1, _options.tries);
    const int threads = std::max(1, options.threads);
    _threads.reserve(std::size_t(threads));
    for (int i = 0; i < threads; ++i) _threads.emplace_back([this] { work(); });
}

TileFetcher::~TileFetcher() {
    {
        const std::lock_guard<std::mutex> lock(_mutex);
        _stop = true;
    }
    _wake.notify_all();
    _idle.notify_all();
    for (std::thread& thread : _threads) thread.join();
}

void TileFetcher::request(std::uint64_t key, const std::string& relativePath, double priority) {
    // NaN would break the queue's ordering; it counts as the lowest priority.
    if (std::isnan(priority)) priority = -std::numeric_limits<double>::infinity();
    {
        const std::lock_guard<std::mutex> lock(_mutex);
        auto found = _keys.find(key);
        if (found != _keys.end()) {
            KeyState& state = found->second;
            if (state.state == State::InFlight) state.discard = false;
            if (state.state == State::Waiting) {
                state.entry.priority = priority;
                state.path = relativePath;
                return;
            }
            if (state.state != State::Pending) return;
            QueueEntry entry = *state.queued;
            _queue.erase(state.queued);
            entry.priority = priority;
            state.queued = _queue.insert(entry).first;
            state.path = relativePath;
            return;
        }
        KeyState state;
        state.path = relativePath;
        state.queued = _queue.insert(QueueEntry{priority, _sequence++, key}).first;
        _keys.emplace(key, std::move(state));
    }
    _wake.notify_one();
}

void TileFetcher::cancel(std::uint64_t key) {
    bool changed = false;
    {
        const std::lock_guard<std::mutex> lock(_mutex);
        auto found = _keys.find(key);
        if (found == _keys.end()) return;
        if (found->second.state == State::Pending) {
            _queue.erase(found->second.queued);
            _keys.erase(found);
            changed = true;
        } else if (found->second.state == State::Waiting) {
            _waiting.erase({found->second.due, key});
            _keys.erase(found);
            changed = true;
        } else if (found->second.state == State::InFlight) {
            found->second.discard = true;
        }
    }
    if (changed) _idle.notify_all();
}

void TileFetcher::forget(std::uint64_t key) {
    cancel(key);
    const std::lock_guard<std::mutex> lock(_mutex);
    auto found = _keys.find(key);
    if (found == _keys.end() || found->second.state != State::Delivered) return;
    _keys.erase(found);
    removeCompleted(key);
}

void TileFetcher::removeCompleted(std::uint64_t key) {
    _completed.erase(std::remove_if(_completed.begin(), _completed.end(),
                                    [key](const FetchedItem& item) { return item.key == key; }),
                     _completed.end());
}

std::vector<FetchedItem> TileFetcher::takeCompleted() {
    std::vector<FetchedItem> items;
    const std::lock_guard<std::mutex> lock(_mutex);
    items.swap(_completed);
    return items;
}

bool TileFetcher::waitIdle(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(_mutex);
    return _idle.wait_for(lock, timeout, [this] {
        return _stop || (_inFlight == 0 && (_paused || (_queue.empty() && _waiting.empty())));
    });
}

void TileFetcher::setPaused(bool paused) {
    {
        const std::lock_guard<std::mutex> lock(_mutex);
        _paused = paused;
    }
    _wake.notify_all();
    _idle.notify_all();
}

std::size_t TileFetcher::pending() const {
    const std::lock_guard<std::mutex> lock(_mutex);
    return _queue.size() + _waiting.size();
}

std::size_t TileFetcher::inFlight() const {
    const std::lock_guard<std::mutex> lock(_mutex);
    return _inFlight;
}

void TileFetcher::queueDueRetries() {
    const Clock::time_point now = Clock::now();
    while (!_waiting.empty() && _waiting.begin()->first <= now) {
        KeyState& state = _keys.at(_waiting.begin()->second);
        _waiting.erase(_waiting.begin());
        state.state = State::Pending;
        state.queued = _queue.insert(state.entry).first;
    }
}

void TileFetcher::work() {
    std::unique_lock<std::mutex> lock(_mutex);
    for (;;) {
        if (_stop) return;
        queueDueRetries();
        if (_paused || _queue.empty()) {
            if (_waiting.empty()) {
                _wake.wait(lock);
            } else {
                // A copy: another worker may erase the entry while this one waits unlocked.
                const Clock::time_point due = _waiting.begin()->first;
                _wake.wait_until(lock, due);
            }
            continue;
        }

        const QueueEntry entry = *_queue.begin();
        _queue.erase(_queue.begin());
        KeyState& state = _keys.at(entry.key);
        state.state = State::InFlight;
        const int tries = ++state.tries;
        const std::string path = state.path;
        ++_inFlight;
        lock.unlock();

        // The source promises not to throw, but a worker must survive anything (bad_alloc, a
        // third-party source): an exception becomes a failed item.
        FetchResult result;
        try {
            result = _source->fetchInterruptible(path, _stop);
        } catch (const std::exception& e) {
            result = failure(path, e.what());
        } catch (...) {
            result = failure(path, "unknown exception");
        }

        lock.lock();
        if (_stop) return;  // aborted: neither delivered nor reported
        auto found = _keys.find(entry.key);
        const bool discard = found == _keys.end() || found->second.discard;
        if (!discard && !result.ok && result.transient && tries < _options.tries) {
            // Again later, after a delay that doubles with each try; no warning yet.
            KeyState& state = found->second;
            auto delay = _options.retryDelay;
            for (int i = 1; i < tries && delay < _options.maxRetryDelay; ++i) delay *= 2;
            delay = std::min(delay, _options.maxRetryDelay);
            state.state = State::Waiting;
            state.entry = entry;
            state.due = Clock::now() + delay;
            _waiting.insert({state.due, entry.key});
            ++_retries;
            --_inFlight;
            _wake.notify_all();  // a worker waits for the earliest retry
            continue;
        }
        if (!result.ok && tries > 1) result.error += " (" + std::to_string(tries) + " tries)";
        bool warn = false;
        if (!discard && !result.ok) {
            std::string where;
            try {
                where = _source->describe(path);
            } catch (...) {
                where = path;
            }
            warn = _reported.insert(where).second;
        }
        if (warn) {
            // The warning goes out before the item is visible, so whoever sees the failed item
            // also sees the message; the key stays in flight meanwhile.
            lock.unlock();
            OSGBTF_NOTIFY(osg::WARN, "osgBTF: " << result.error);
            lock.lock();
            if (_stop) return;
            found = _keys.find(entry.key);
        }
        --_inFlight;
        if (found != _keys.end()) {
            if (found->second.discard) {
                _keys.erase(found);
            } else {
                found->second.state = State::Delivered;
                if (result.ok) _bytesReceived += result.data.size();
                _completed.push_back(FetchedItem{entry.key, path, std::move(result)});
            }
        }
        _idle.notify_all();
    }
}

}  // namespace osgBTF

// osgBTF BSVTF streaming (Schwartz et al. 2013 section 6): fetching the files of a tile set
// (TileSet.h: index.bsvtf, u/G.half, tiles/G/L/X_Y.tile) from a local folder or from any static
// HTTP server, in the order of the scheduler's priorities, without blocking the render thread.
//
// Why plain files over plain HTTP: one file per tile lets any stock server (nginx, a CDN, S3)
// stream a material; no custom protocol, no server code. libcurl's easy interface does the HTTP
// (redirects, keep-alive per thread, proxies from the environment, https).
//
// Why a fetcher of its own: the render thread must never wait on the network. It requests keys
// with priorities (a tile's P = w v, a U packet's vote sum) each frame, re-prioritises what is
// still pending, and takes what has arrived; one or a few worker threads fetch the highest
// priority first. Tiles are a few KB, so a small pool hides latency well enough, and one thread
// keeps the order exact.
//
// Failures: a network fails in many ways (refused, stalled, 404, 500, truncated, huge). Each is a
// failed item with a message "URL-or-path: problem", never an exception or a crash; the message
// goes to OSG's WARN once per URL (a missing tile requested every frame must not flood the log),
// and a failed key is not fetched again until the caller forget()s it. Failures that a second try
// may not repeat (refused, reset or stalled connections, HTTP 5xx, 408 and 429: a server
// restarting, overloaded or behind a flaky link) are tried again first, after delays that double
// (TileFetcherOptions::tries, retryDelay), before they count as failed: a server that comes back
// within that time is used again, and one that does not costs one warning. A 404, a redirect
// loop or a response too large fail at once: the same request gets the same answer.
//
// Stopping: the destructor must not hang on a dead server. Transfers check a stop flag from
// libcurl's progress callback, which runs at least about once a second even when no byte arrives,
// and a transfer that gets less than 1 byte/s for stallSeconds fails as stalled.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace osgBTF {

struct FetchResult {
    bool ok = false;
    std::vector<std::uint8_t> data;
    /** When !ok: "WHERE: problem", WHERE the source's describe(path), e.g.
     *  "http://127.0.0.1:1234/x/tiles/0/0/0_0.tile: HTTP 404", "...: connection refused",
     *  "...: timed out (no data for 5 s)", "/data/x/index.bsvtf: cannot open: No such file or
     *  directory". */
    std::string error;
    /** When !ok: whether trying again may succeed (the connection failed, stalled or was cut, or
     *  the server answered 5xx, 408 or 429), as opposed to an answer that a retry repeats. */
    bool transient = false;
};

/** Where the files of one tile set come from; fetch() may run in several threads at once. */
class TileSource {
public:
    virtual ~TileSource() = default;
    /** The whole file at `relativePath` (e.g. "tiles/0/2/1_3.tile"). Never throws for a missing
     *  or broken file or connection: that is a failed result. */
    virtual FetchResult fetch(const std::string& relativePath) = 0;
    /** The same, giving up soon (within about a second) once `stop` becomes true, with the error
     *  "WHERE: cancelled". The default ignores `stop` (right for local reads, which are short). */
    virtual FetchResult fetchInterruptible(const std::string& relativePath,
                                           const std::atomic<bool>& stop);
    /** The URL or file path of `relativePath`, for messages. */
    virtual std::string describe(const std::string& relativePath) const = 0;
};

/** A tile set in a local folder (what `btf tiles` writes). */
class FolderTileSource : public TileSource {
public:
    explicit FolderTileSource(std::string folder);
    /** Missing, unreadable or not a regular file: "PATH: cannot open: <strerror>" etc. */
    FetchResult fetch(const std::string& relativePath) override;
    std::string describe(const std::string& relativePath) const override;

private:
    std::string _folder;
};

struct HttpOptions {
    /** Seconds to establish the TCP (and TLS) connection. */
    long connectTimeoutSeconds = 5;
    /** A transfer that receives less than 1 byte/s for this long fails as "timed out (no data
     *  for N s)". No total time limit: a large U packet over a slow but live link may take long. */
    long stallSeconds = 5;
    /** A larger response fails ("response larger than N bytes"): a misconfigured server must not
     *  exhaust memory (a U packet of 151^2 directions is 534 KiB, a tile a few KB). */
    std::size_t maxBytes = std::size_t(64) << 20;
};

/** A tile set below `baseUrl` on an HTTP(S) server (e.g. "http://host/materials/wool"): GET
 *  baseUrl/relativePath. Up to 3 redirects (http and https only); a final status other than 2xx is
 *  "URL: HTTP <status>". One libcurl handle per thread, reused (keep-alive) across fetches. */
class HttpTileSource : public TileSource {
public:
    explicit HttpTileSource(std::string baseUrl, HttpOptions options = {});
    FetchResult fetch(const std::string& relativePath) override;
    FetchResult fetchInterruptible(const std::string& relativePath,
                                   const std::atomic<bool>& stop) override;
    /** baseUrl "/" relativePath, characters outside [A-Za-z0-9-._~/] percent-encoded. */
    std::string describe(const std::string& relativePath) const override;
    const HttpOptions& options() const { return _options; }

private:
    std::string _baseUrl;
    HttpOptions _options;
};

/** "http://..." or "https://..." (case-insensitive scheme): HttpTileSource with default options;
 *  anything else is a folder. */
std::unique_ptr<TileSource> openTileSource(const std::string& location);

struct FetchedItem {
    std::uint64_t key = 0;
    std::string path;  ///< the relative path requested
    FetchResult result;
};

struct TileFetcherOptions {
    /** Worker threads (at least 1). With 1, files arrive in exact priority order; more overlap
     *  the latency of several requests (2-4 suit an HTTP server; each keeps its own connection). */
    int threads = 1;
    /** Start with the workers paused (see setPaused): e.g. to queue a batch first so it is
     *  fetched strictly by priority, not first-come. */
    bool paused = false;
    /** Tries of a file whose fetch fails transiently (FetchResult::transient) before it is
     *  delivered as failed (at least 1: no retry). */
    int tries = 5;
    /** Delay before the second try; each later one waits twice as long as the one before, at
     *  most maxRetryDelay (defaults: 0.5, 1, 2 and 4 s, so a server away for up to ~7 s is used
     *  again). Meanwhile the key is pending: it counts for pending() and waitIdle(). */
    std::chrono::milliseconds retryDelay{500};
    std::chrono::milliseconds maxRetryDelay{8000};
};

/** Fetches requested files of one source in the background, highest priority first.
 *
 *  A key (the caller's id of a file, e.g. material, group, level and tile packed together) is in
 *  one of these states: unknown, pending (queued with a priority), in flight, or delivered (its
 *  FetchedItem, ok or failed, went to the completed list). request() moves unknown to pending and
 *  only updates a pending key's priority and path; delivered and in-flight keys stay as they are,
 *  so the render thread may request everything it wants every frame. forget() makes a key
 *  unknown again, so it can be fetched anew (after a failure, or after the cache dropped it).
 *
 *  Thread-safe: any thread may call any member. Workers sleep on a condition variable when there
 *  is nothing to do. */
class TileFetcher {
public:
    explicit TileFetcher(std::shared_ptr<TileSource> source, TileFetcherOptions options = {});
    /** Stops the workers: pending requests are dropped, transfers in flight are aborted (within
     *  about a second, libcurl's progress interval) and their results discarded. */
    ~TileFetcher();
    TileFetcher(const TileFetcher&) = delete;
    TileFetcher& operator=(const TileFetcher&) = delete;

    /** Queues `relativePath` under `key` with `priority` (higher first; equal priorities in the
     *  order first requested; NaN counts as lowest). A pending key gets the new priority and path;
     *  an in-flight or delivered key is left alone (a cancelled in-flight key is wanted again). */
    void request(std::uint64_t key, const std::string& relativePath, double priority);
    /** Drops a pending key; the result of an in-flight one is discarded when it arrives (the
     *  transfer itself runs on: tiles are small). A delivered key stays delivered. */
    void cancel(std::uint64_t key);
    /** cancel(), and a delivered key becomes unknown (its item is removed from the completed list
     *  if not taken yet), so that a later request() fetches it again. */
    void forget(std::uint64_t key);

    /** The items delivered since the last call, in the order they completed. Never blocks on I/O
     *  (only on the fetcher's short lock): for the render thread. */
    std::vector<FetchedItem> takeCompleted();
    /** Blocks until nothing is pending or in flight, or until `timeout`; true when idle. (While
     *  paused, pending requests do not count.) For tools and tests; the render thread polls. */
    bool waitIdle(std::chrono::milliseconds timeout);

    /** Pauses or resumes taking requests; a transfer in flight completes. */
    void setPaused(bool paused);

    /** Fetches tried again after a transient failure, since the start. */
    std::uint64_t retries() const { return _retries.load(); }
    /** Sum of the sizes of the files delivered successfully. */
    std::uint64_t bytesReceived() const { return _bytesReceived.load(); }
    std::size_t pending() const;
    std::size_t inFlight() const;
    TileSource& source() const { return *_source; }

private:
    struct QueueEntry {
        double priority;
        std::uint64_t sequence;  ///< order of the first request, for ties
        std::uint64_t key;
        bool operator<(const QueueEntry& other) const;
    };
    using Clock = std::chrono::steady_clock;
    /** Waiting: failed transiently, queued again at `due` (in _waiting, not in _queue). */
    enum class State { Pending, Waiting, InFlight, Delivered };
    struct KeyState {
        State state = State::Pending;
        std::string path;
        std::set<QueueEntry>::iterator queued;  ///< valid while Pending
        bool discard = false;                   ///< InFlight: drop the result (cancelled)
        int tries = 0;                          ///< fetches made so far
        QueueEntry entry{};                     ///< Waiting: its place in the queue once due
        Clock::time_point due{};                ///< Waiting
    };

    void work();
    void removeCompleted(std::uint64_t key);
    /** Moves the waiting keys whose time has come to the queue. */
    void queueDueRetries();

    std::shared_ptr<TileSource> _source;
    mutable std::mutex _mutex;
    std::condition_variable _wake;  ///< workers: a request, resume or stop
    std::condition_variable _idle;  ///< waitIdle: something completed
    std::set<QueueEntry> _queue;
    std::set<std::pair<Clock::time_point, std::uint64_t>> _waiting;  ///< retries by due time
    TileFetcherOptions _options;
    std::map<std::uint64_t, KeyState> _keys;
    std::vector<FetchedItem> _completed;
    std::set<std::string> _reported;  ///< describe(path) of every failure already warned about
    std::uint64_t _sequence = 0;
    std::size_t _inFlight = 0;
    bool _paused = false;
    std::atomic<bool> _stop{false};
    std::atomic<std::uint64_t> _bytesReceived{0};
    std::atomic<std::uint64_t> _retries{0};
    std::vector<std::thread> _threads;
};

}  // namespace osgBTF

#pragma once
// Objects shared by key while anything besides the cache holds them: the materials opened from
// files, the coordinate-map textures and the terminator textures that many MaterialNodes use.
//
// The cache holds each object with a ref_ptr and drops the ones nothing else holds, as osgDB's
// object cache does (removeUnreferencedObjectsInCache), instead of observing them with an
// osg::observer_ptr. An observer shares the object's osg::ObserverSet, which ~Referenced
// releases and frees inside libosg, whose copy of OSG's inline atomics ThreadSanitizer does not
// see: every observer dropped here while another thread deleted the object was reported as a
// race (docs/reliability.md "Threads"). Here each change of an object's count made by
// the cache is one of OSG's inline atomics compiled into osgBTF, which the sanitizer sees, and an
// object is deleted by its last outside holder or, once only the cache holds it, by the cache.
#include <condition_variable>
#include <map>
#include <mutex>
#include <utility>
#include <vector>

#include <osg/ref_ptr>

namespace osgBTF {

/** `Stamp` tells whether a cached object is still the one wanted for its key (a file's size and
 *  modification time, say); a different stamp makes a new object that replaces the entry. */
template <class Key, class T, class Stamp>
class SharedObjects {
public:
    /** The cached object of `key` when its stamp equals `stamp`, else `make()` (called outside
     *  the lock; threads asking for the same key and stamp meanwhile wait for it instead of
     *  making their own; when it throws, they try themselves). Drops unused objects first. */
    template <class Make>
    osg::ref_ptr<T> get(const Key& key, const Stamp& stamp, Make&& make) {
        std::vector<osg::ref_ptr<T>> unused;  // deleted after the lock is released
        std::unique_lock<std::mutex> lock(_mutex);
        takeUnused(unused);
        for (;;) {
            const auto it = _entries.find(key);
            if (it == _entries.end() || !(it->second.stamp == stamp)) break;
            if (it->second.object) return it->second.object;
            _made.wait(lock);  // another thread is making this object
        }
        _entries[key] = Entry{stamp, nullptr};
        lock.unlock();
        unused.clear();
        osg::ref_ptr<T> object;
        try {
            object = make();
        } catch (...) {
            finish(key, stamp, nullptr);
            throw;
        }
        finish(key, stamp, object);
        return object;
    }

    /** Deletes the objects only the cache holds; returns how many. */
    std::size_t releaseUnused() {
        std::vector<osg::ref_ptr<T>> unused;
        {
            std::lock_guard<std::mutex> lock(_mutex);
            takeUnused(unused);
        }
        return unused.size();  // deleted here, outside the lock
    }

private:
    struct Entry {
        Stamp stamp;
        osg::ref_ptr<T> object;  // null while a thread makes it
    };

    /** Moves the objects only the cache holds out of it (the caller holds the lock). The count
     *  is read with ref(), an atomic increment: referenceCount() is a plain read, which
     *  ThreadSanitizer reports against another thread's atomic unref. Nobody can take a new
     *  reference but through the cache, under the lock, so a count of 2 (the entry's and this
     *  one) cannot grow behind our back. */
    void takeUnused(std::vector<osg::ref_ptr<T>>& unused) {
        for (auto it = _entries.begin(); it != _entries.end();) {
            T* object = it->second.object.get();
            const bool onlyHere = object && object->ref() == 2;
            if (object) object->unref();  // back to the entry's own reference: never deletes
            if (onlyHere) {
                unused.push_back(std::move(it->second.object));
                it = _entries.erase(it);
            } else {
                ++it;
            }
        }
    }

    /** Stores what make() gave (or forgets the attempt on null) unless a newer stamp replaced
     *  the entry meanwhile, and wakes the threads waiting for it. */
    void finish(const Key& key, const Stamp& stamp, const osg::ref_ptr<T>& object) {
        {
            std::lock_guard<std::mutex> lock(_mutex);
            const auto it = _entries.find(key);
            if (it != _entries.end() && it->second.stamp == stamp && !it->second.object) {
                if (object)
                    it->second.object = object;
                else
                    _entries.erase(it);
            }
        }
        _made.notify_all();
    }

    std::mutex _mutex;
    std::condition_variable _made;
    std::map<Key, Entry> _entries;
};

}  // namespace osgBTF

#include "loaders/Ubo2003.h"

#include <unistd.h>
#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <regex>
#include <set>
#include <sstream>
#include <vector>

#include <Imath/half.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>
#include <zip.h>

#include "core/Error.h"
#include "core/ImageCodecs.h"
#include "core/Progress.h"
#include "core/SizeGuard.h"
#include "loaders/ImageSet.h"

namespace osgBTF {

namespace {

namespace fs = std::filesystem;

/** A name that carries the direction tokens but not in the accepted form, e.g. a ".txt" or a
 *  "_small.jpg" variant: silently skipping it could hide a damaged archive, so it is an error. */
bool looksLikeBtfName(const std::string& basename) {
    static const std::regex tokens(R"(tl\d{3} pl\d{3} tv\d{3} pv\d{3})", std::regex::icase);
    return std::regex_search(basename, tokens);
}

/** An image of the archive with what its name says. */
struct Member : ImageSetEntry {
    Ubo2003Name parsed;
};

DirectionSet buildSet(const std::set<std::pair<int, int>>& found, const std::string& name) {
    const DirectionSet bonn = DirectionSet::bonn81();
    std::set<std::pair<int, int>> bonnSet;
    for (const Direction& d : bonn.directions())
        bonnSet.emplace(int(std::lround(d.theta)), int(std::lround(d.phi)));
    if (found == bonnSet) return bonn;
    std::vector<Direction> directions;
    for (const auto& [theta, phi] : found) directions.push_back({float(theta), float(phi)});
    return DirectionSet(name, std::move(directions));
}

std::string tokens(int lt, int lp, int vt, int vp) {
    char text[64];
    std::snprintf(text, sizeof text, "tl%03d pl%03d tv%03d pv%03d", lt, lp, vt, vp);
    return text;
}

}  // namespace

bool parseUbo2003Name(const std::string& memberPath, Ubo2003Name& name) {
    static const std::regex pattern(
        R"(^(?:(\d{5}) )?tl(\d{3}) pl(\d{3}) tv(\d{3}) pv(\d{3})\.([A-Za-z]+)$)");
    const std::string base = imageSetBasename(memberPath);
    std::smatch m;
    if (!std::regex_match(base, m, pattern)) return false;
    const std::string ext = asciiLower(m[6].str());
    if (ext != "jpg" && ext != "jpeg" && ext != "png" && ext != "hdr" && ext != "exr") return false;
    name.index = m[1].matched ? std::stoi(m[1].str()) : -1;
    name.lightTheta = std::stoi(m[2].str());
    name.lightPhi = std::stoi(m[3].str());
    name.viewTheta = std::stoi(m[4].str());
    name.viewPhi = std::stoi(m[5].str());
    name.extension = ext;
    return true;
}

bool mayBeUbo2003(const std::string& path) {
    try {
        ImageSetSource source(path);
        for (const auto& entry : source.names()) {
            Ubo2003Name parsed;
            const std::string& name = entry.first;
            if (parseUbo2003Name(name, parsed) || looksLikeBtfName(imageSetBasename(name)))
                return true;
        }
        return false;
    } catch (const Error&) {
        return true;  // cannot be opened: loadUbo2003 says why
    }
}

MeasuredBtf loadUbo2003(const std::string& path, const LoadOptions& options) {
    ImageSetSource source(path);

    std::vector<Member> members;
    for (const auto& [name, zipIndex] : source.names()) {
        Member member;
        member.name = name;
        member.zipIndex = zipIndex;
        if (!parseUbo2003Name(name, member.parsed)) {
            if (looksLikeBtfName(imageSetBasename(name)))
                fail(path, "member '" + name +
                               "' looks like a BTF image but its name is not "
                               "'[NNNNN ]tlTTT plPPP tvTTT pvPPP.<jpg|jpeg|png|hdr|exr>'");
            continue;
        }
        member.extension = member.parsed.extension;
        const Ubo2003Name& p = member.parsed;
        for (auto [what, value, limit] :
             {std::tuple{"light theta", p.lightTheta, 90},
              std::tuple{"view theta", p.viewTheta, 90}, std::tuple{"light phi", p.lightPhi, 359},
              std::tuple{"view phi", p.viewPhi, 359}})
            if (value > limit)
                fail(path, "member '" + name + "': " + what + " " + std::to_string(value) +
                               " is outside [0, " + std::to_string(limit) + "] degrees");
        members.push_back(std::move(member));
    }
    if (members.empty())
        fail(path, "no BTF images (tlTTT plPPP tvTTT pvPPP.jpg) found among " +
                       std::to_string(source.names().size()) + " entries");

    std::set<std::pair<int, int>> lightSet, viewSet;
    for (const Member& m : members) {
        lightSet.emplace(m.parsed.lightTheta, m.parsed.lightPhi);
        viewSet.emplace(m.parsed.viewTheta, m.parsed.viewPhi);
    }
    DirectionSet lights = buildSet(lightSet, "ubo2003-lights");
    DirectionSet views = buildSet(viewSet, "ubo2003-views");
    std::map<std::pair<int, int>, int> lightIndex, viewIndex;
    for (std::size_t i = 0; i < lights.size(); ++i)
        lightIndex[{int(std::lround(lights[i].theta)), int(std::lround(lights[i].phi))}] = int(i);
    for (std::size_t i = 0; i < views.size(); ++i)
        viewIndex[{int(std::lround(views[i].theta)), int(std::lround(views[i].phi))}] = int(i);

    const std::size_t nL = lights.size(), nV = views.size();
    // Up to 91 x 360 directions each: a grid of nL x nV slots is sized only once the members
    // fill it, since a few thousand names could otherwise ask for gigabytes of empty slots.
    std::map<std::size_t, int> slots;
    for (std::size_t i = 0; i < members.size(); ++i) {
        Member& m = members[i];
        m.light = lightIndex.at({m.parsed.lightTheta, m.parsed.lightPhi});
        m.view = viewIndex.at({m.parsed.viewTheta, m.parsed.viewPhi});
        const auto [slot, added] = slots.emplace(std::size_t(m.light) * nV + m.view, int(i));
        if (!added)
            fail(path, "members '" + members[slot->second].name + "' and '" + m.name +
                           "' hold the same image (" +
                           tokens(m.parsed.lightTheta, m.parsed.lightPhi, m.parsed.viewTheta,
                                  m.parsed.viewPhi) +
                           ")");
    }
    const std::size_t missing = nL * nV - slots.size();
    if (missing > 0) {
        // The first empty slot: at most slots.size() slots precede it.
        std::size_t first = 0;
        for (const auto& entry : slots) {
            if (entry.first != first) break;
            ++first;
        }
        const Direction& l = lights[first / nV];
        const Direction& v = views[first % nV];
        fail(path, std::to_string(missing) + " of " + std::to_string(nL * nV) +
                       " (light, view) images are missing, e.g. '" +
                       tokens(int(std::lround(l.theta)), int(std::lround(l.phi)),
                              int(std::lround(v.theta)), int(std::lround(v.phi))) +
                       "' (found " + std::to_string(nL) + " light and " + std::to_string(nV) +
                       " view directions)");
    }

    std::vector<ImageSetEntry> entries(members.begin(), members.end());
    // The Bonn data are linear (seed paper 004) unless the caller says otherwise.
    const LoadOptions::DecodeCurve curve = options.curve == LoadOptions::DecodeCurve::Auto
                                               ? LoadOptions::DecodeCurve::Linear
                                               : options.curve;
    return decodeImageSet(source, entries, views, lights, options, curve);
}

}  // namespace osgBTF

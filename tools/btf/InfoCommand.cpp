// btf info FILE: what a measured BTF holds, and whether its values are sane.
#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>

#include <nlohmann/json.hpp>

#include "core/MeasuredBtf.h"
#include "loaders/LoadBtf.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

namespace {

struct ValueStats {
    double minimum[3], maximum[3], sum[3];
    std::size_t perChannel = 0, nan = 0, inf = 0;
};

ValueStats scan(const MeasuredBtf& btf) {
    ValueStats s;
    for (int c = 0; c < 3; ++c) {
        s.minimum[c] = std::numeric_limits<double>::infinity();
        s.maximum[c] = -s.minimum[c];
        s.sum[c] = 0;
    }
    for (std::size_t v = 0; v < btf.viewCount(); ++v)
        for (std::size_t l = 0; l < btf.lightCount(); ++l) {
            const std::vector<float> image = btf.image(v, l);
            for (std::size_t i = 0; i < image.size(); ++i) {
                const float x = image[i];
                const int c = int(i % 3);
                if (std::isnan(x)) {
                    ++s.nan;
                } else if (std::isinf(x)) {
                    ++s.inf;
                } else {
                    s.minimum[c] = std::min(s.minimum[c], double(x));
                    s.maximum[c] = std::max(s.maximum[c], double(x));
                    s.sum[c] += x;
                }
            }
        }
    s.perChannel = btf.texelCount() * btf.viewCount() * btf.lightCount();
    return s;
}

nlohmann::json directionJson(const DirectionSet& set) {
    float lo = 90, hi = 0;
    for (const Direction& d : set.directions()) {
        lo = std::min(lo, d.theta);
        hi = std::max(hi, d.theta);
    }
    return {{"name", set.name()}, {"count", set.size()}, {"theta_min", lo}, {"theta_max", hi}};
}

}  // namespace

Runner addInfoCommand(CLI::App& app, CommonOptions& common) {
    auto* command = app.add_subcommand("info",
                                       "Print sizes, direction sets, value range, memory "
                                       "and NaN/Inf count of a measured BTF");
    struct Options {
        std::string input;
        bool json = false;
    };
    auto options = std::make_shared<Options>();
    std::string& input = options->input;
    command->add_option("FILE", input, "UBO2003/ATRIUM zip or folder, or UBO2014 .btf")->required();
    command->add_flag("--json", options->json, "Print JSON instead of text");
    addLoadOptions(*command, common);
    return [&common, options] {
        const std::string& input = options->input;
        const MeasuredBtf btf = loadMeasuredBtf(input, common.loadOptions());
        const ValueStats s = scan(btf);
        const std::uint64_t raw8bit =
            std::uint64_t(btf.texelCount()) * btf.viewCount() * btf.lightCount() * 3;
        nlohmann::json out = {
            {"file", input},
            {"width", btf.width()},
            {"height", btf.height()},
            {"views", directionJson(btf.views())},
            {"lights", directionJson(btf.lights())},
            {"storage", btf.storage() == Storage::Float ? "float" : "half"},
            {"memory_bytes", btf.memoryBytes()},
            {"raw_8bit_bytes", raw8bit},
            {"nan_count", s.nan},
            {"inf_count", s.inf},
        };
        const std::size_t perChannel = s.perChannel;
        for (int c = 0; c < 3; ++c) {
            const char* name = c == 0 ? "R" : c == 1 ? "G" : "B";
            out["range"][name] = {{"min", s.minimum[c]},
                                  {"max", s.maximum[c]},
                                  {"mean", perChannel ? s.sum[c] / double(perChannel) : 0.0}};
        }
        if (options->json) {
            std::cout << out.dump(2) << "\n";
            return;
        }
        std::cout << std::fixed << std::setprecision(4);
        std::cout << "file:     " << input << "\n"
                  << "texels:   " << btf.width() << " x " << btf.height() << "\n";
        for (const char* key : {"views", "lights"}) {
            const auto& d = out[key];
            std::cout << (std::string(key) + ":").append(10 - std::string(key).size() - 1, ' ')
                      << d["count"] << " (" << d["name"].get<std::string>() << ", theta "
                      << d["theta_min"].get<float>() << " to " << d["theta_max"].get<float>()
                      << " deg)\n";
        }
        std::cout << "images:   " << btf.viewCount() * btf.lightCount() << " (view, light) pairs\n"
                  << "storage:  " << out["storage"].get<std::string>() << ", "
                  << formatBytes(btf.memoryBytes()) << " in memory (" << formatBytes(raw8bit)
                  << " as 8-bit RGB)\n";
        for (const char* name : {"R", "G", "B"}) {
            const auto& r = out["range"][name];
            std::cout << "range " << name << ":  min " << r["min"].get<double>() << "  max "
                      << r["max"].get<double>() << "  mean " << r["mean"].get<double>() << "\n";
        }
        std::cout << "non-finite: " << s.nan << " NaN, " << s.inf << " Inf\n";
    };
}

}  // namespace osgBTF::tool

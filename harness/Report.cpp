#include "harness/Report.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/MeasuredBtf.h"

namespace osgBTF {

namespace {

std::string fixed(double value, int decimals) {
    if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
    if (std::isnan(value)) return "nan";
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
    return buffer;
}

std::string general(double value, int digits = 5) {
    if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
    return buffer;
}

std::string full(double value) {
    return general(value, 17);
}

std::string optionText(const MethodResult& m) {
    std::string text;
    for (const auto& [key, value] : m.options)
        text += (text.empty() ? "" : " ") + key + "=" + value;
    return text.empty() ? "defaults" : text;
}

std::string cell(const std::string& text) {
    std::string out;
    for (char c : text)
        out += c == '|' ? std::string("\\|") : c == '\n' ? std::string(" ") : std::string(1, c);
    return out;
}

std::string csvField(const std::string& text) {
    if (text.find_first_of(",\"\n") == std::string::npos) return text;
    std::string out = "\"";
    for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
    return out + "\"";
}

nlohmann::json number(double value) {
    if (std::isfinite(value)) return value;
    return std::isnan(value) ? "nan" : value > 0 ? "inf" : "-inf";
}

std::string passDescription(const CompareResult& r) {
    return std::to_string(r.pass.width) + "x" + std::to_string(r.pass.height) + " pixels, " +
           std::to_string(r.pass.lights) + " light" + (r.pass.lights == 1 ? "" : "s") +
           ", median of " + std::to_string(r.pass.frames) + " frames after " +
           std::to_string(r.pass.warmupFrames) + " warm-up frames, texture repeated " +
           general(r.pass.textureScale, 3) + " times across the viewport";
}

}  // namespace

std::string reportMarkdown(const CompareResult& r) {
    std::ostringstream md;
    const std::string name = std::filesystem::path(r.input).filename().string();
    md << "# BTF method comparison: " << name << "\n\n"
       << "Input `" << r.input << "`: " << r.width << "x" << r.height << " texels, " << r.views
       << " views x " << r.lights << " lights. Raw data: " << general(r.rawBytesPerTexel, 8)
       << " bytes per texel (8-bit RGB per measured value), " << formatBytes(r.rawTotalBytes)
       << " in all.\n\n";
    if (r.errorTexels < std::size_t(r.width) * std::size_t(r.height))
        md << "**Errors are computed on a random subsample of " << r.errorTexels << " of "
           << std::size_t(r.width) * std::size_t(r.height)
           << " texels** (every view and light pair of each; the same texels for every method; "
              "grey in the error maps: not compared).\n\n";
    md << "GPU: " << r.gpuNote << ".\n\n"
       << "**" << r.recommendation << ".**\n\n"
       << "Definitions of every column: harness/README.md in the osgBTF sources.\n\n";

    md << "## Table 1: error\n\n"
       << "Per-texel error (Meseth et al. 2003, sec. 4.1: mean over all " << r.views * r.lights
       << " measured (view, light) pairs of |measured - model| in RGB, 8-bit data scaled to "
          "[0, 1]) as average / minimum / maximum over texels; RMSE over every channel value; "
          "PSNR with peak 1. From the CPU evaluator. The GPU column is the largest |GPU - CPU| "
          "over "
       << r.spotCheckPairs.size() << " (view, light) images.\n\n"
       << "| method | options | avg | min | max | RMSE | PSNR dB | NaN/Inf | max GPU-CPU |\n"
       << "|---|---|---|---|---|---|---|---|---|\n";
    for (const MethodResult& m : r.methods) {
        md << "| " << m.label() << " | " << cell(optionText(m)) << " | ";
        if (m.failed) {
            md << cell(m.failure) << " | | | | | | |\n";
            continue;
        }
        md << fixed(m.error.average, 5) << " | " << fixed(m.error.minimum, 5) << " | "
           << fixed(m.error.maximum, 5) << " | " << fixed(m.error.rmse, 5) << " | "
           << fixed(m.error.psnr, 2) << " | " << m.error.nonFiniteValues << " | "
           << (m.gpuCpuMaxDifference >= 0 ? general(m.gpuCpuMaxDifference, 3) : "n/a") << " |\n";
    }

    md << "\n### Held-out directions\n\n"
       << "Each method fitted again without some of the measured directions (" << r.holdoutNote
       << "; whole directions, the split of `btf batch`) and scored on the pairs left out: the "
          "per-texel error, RMSE and PSNR as above, and the SSIM (Wang et al. 2004: 11 x 11 "
          "Gaussian window, sigma 1.5, K1 0.01, K2 0.03, range 1) of up to 8 whole left-out "
          "images, the figures RTI papers report for relighting.\n\n";
    if (r.holdoutFraction > 0) {
        md << "| method | held-out avg | RMSE | PSNR dB | SSIM | images | fit s |\n"
           << "|---|---|---|---|---|---|---|\n";
        for (const MethodResult& m : r.methods) {
            md << "| " << m.label() << " | ";
            if (m.failed || !m.heldOutFailure.empty()) {
                md << cell(m.failed ? m.failure : m.heldOutFailure) << " | | | | | |\n";
                continue;
            }
            md << fixed(m.heldOut.error.average, 5) << " | " << fixed(m.heldOut.error.rmse, 5)
               << " | " << fixed(m.heldOut.error.psnr, 2) << " | " << fixed(m.heldOut.ssim, 4)
               << " | " << m.heldOut.imagesScored << " | "
               << (m.heldOutFitSeconds >= 0 ? fixed(m.heldOutFitSeconds, 2) : "") << " |\n";
        }
    }
    md << "\n## Table 2: memory\n\n"
       << "Storage as Meseth et al. 2003, Table 2, counts it (Material::memory(): per-texel arrays "
          "fully, "
          "shared tables divided by the texel count). Compression ratio = raw bytes per texel ("
       << general(r.rawBytesPerTexel, 8) << ") / bytes per texel.\n\n"
       << "| method | values/texel | bytes/texel | total | compression ratio |\n"
       << "|---|---|---|---|---|\n"
       << "| raw data | " << general(double(r.views * r.lights * 3), 8) << " | "
       << general(r.rawBytesPerTexel, 8) << " | " << formatBytes(r.rawTotalBytes) << " | 1 |\n";
    for (const MethodResult& m : r.methods) {
        md << "| " << m.label() << " | ";
        if (m.failed) {
            md << cell(m.failure) << " | | | |\n";
            continue;
        }
        md << fixed(m.memory.valuesPerTexel, 1) << " | " << fixed(m.memory.bytesPerTexel, 1)
           << " | " << formatBytes(m.memory.totalBytes) << " (" << m.memory.totalBytes
           << " bytes) | " << general(m.compressionRatio, 4) << " |\n";
    }

    for (const MethodResult& m : r.methods)
        if (!m.failed && m.memory.sharedBytes > 0)
            md << "\n"
               << m.label() << ": " << formatBytes(m.memory.sharedBytes) << " ("
               << m.memory.sharedBytes
               << " bytes) of the total are tables shared by all texels, counted above divided "
                  "by the texel count.\n";

    md << "\n## Table 3: pass cost\n\n"
       << "ALU / TEX: static count of the fragment shader (harness/MaterialShaderCost.h), fixed + "
          "per light, and the total at "
       << r.pass.lights << " light" << (r.pass.lights == 1 ? "" : "s") << ". ";
    if (r.gpuRan && !r.calibrations.empty()) {
        const std::string clock = r.calibrations.front().empty.clock;
        md << "Time per pass: " << passDescription(r) << "; clock: " << clock
           << (clock == "GL_TIME_ELAPSED"
                   ? " (GPU timer queries around the camera's draw)"
                   : " (software renderer: wall time of a frame ending with glFinish; its GL "
                     "timer queries are meaningless)")
           << ", renderer " << r.glRenderer << ". Each target is a renderbuffer of that format "
           << "(never read back) and is timed on its own: its empty pass (the patch with a "
              "constant colour: clear, raster, write), its calibration pass, then every method. "
              "*- empty* = the method's pass minus the empty pass of the same target: what its "
              "shading costs. Calibration: ";
        for (std::size_t i = 0; i < r.calibrations.size(); ++i) {
            const Calibration& c = r.calibrations[i];
            md << (i ? "; " : "") << c.target.name << " " << c.fetchCount
               << " RGBA32F texelFetch per pixel took " << fixed(c.fetches.ms, 3)
               << " ms against an empty pass of " << fixed(c.empty.ms, 3) << " ms: "
               << (c.fetchesPerSecond > 0 ? general(c.fetchesPerSecond / 1e9, 4) + " G fetches/s"
                                          : std::string("no fetch rate (not above the empty "
                                                        "pass)"));
        }
        md << ". Floor = TEX total x pixels / that rate (the reads alone); x floor = (method - "
              "empty) / floor. A difference near 0 or below is within the clock's noise.\n\n";
    } else {
        md << "No pass times: " << r.gpuNote << ".\n\n";
    }
    const std::vector<PassTarget>& targets = r.pass.targets;
    md << "| method | ALU fixed + per light | TEX fixed + per light | ALU total | TEX total | "
          "count rule |";
    for (const PassTarget& t : targets)
        md << " " << t.name << " ms | " << t.name << " - empty | " << t.name << " x floor |";
    md << "\n|---|---|---|---|---|---|" << [&] {
        std::string cells;
        for (std::size_t i = 0; i < targets.size(); ++i) cells += "---|---|---|";
        return cells;
    }() << "\n";
    if (r.gpuRan && r.calibrations.size() == targets.size()) {
        md << "| *empty pass* | 0 + 0 | 0 + 0 | 0 | 0 | no material |";
        for (const Calibration& c : r.calibrations) md << " " << fixed(c.empty.ms, 3) << " | 0 | |";
        md << "\n| *calibration* | | " << r.calibrations.front().fetchCount << " + 0 | | "
           << r.calibrations.front().fetchCount << " | RGBA32F texelFetch |";
        for (const Calibration& c : r.calibrations)
            md << " " << fixed(c.fetches.ms, 3) << " | " << fixed(c.fetches.ms - c.empty.ms, 3)
               << " | " << (c.fetchesPerSecond > 0 ? "1.00" : "n/a") << " |";
        md << "\n";
    }
    for (const MethodResult& m : r.methods) {
        md << "| " << m.label() << " | ";
        if (m.failed) {
            md << cell(m.failure) << " | | | | |" << std::string(3 * targets.size(), '|') << "\n";
            continue;
        }
        if (m.cost.counted)
            md << m.cost.fixedAlu << " + " << m.cost.perLightAlu << " | " << m.cost.fixedTex
               << " + " << m.cost.perLightTex << " | " << m.cost.alu(r.pass.lights) << " | "
               << m.cost.tex(r.pass.lights) << " | " << cell(m.cost.formula) << " |";
        else
            md << "n/a | n/a | n/a | n/a | not counted |";
        for (std::size_t i = 0; i < targets.size(); ++i) {
            const MethodPass* p =
                i < m.passes.size() && m.passes[i].measured() ? &m.passes[i] : nullptr;
            if (!p) {
                md << " n/a | n/a | n/a |";
                continue;
            }
            md << " " << fixed(p->pass.ms, 3) << " | " << fixed(p->shadingMs, 3) << " | "
               << (p->floorMs > 0 ? fixed(p->floorRatio, 2) : "n/a") << " |";
        }
        md << "\n";
    }

    md << "\n## Fitting\n\n"
       << "Each fit runs as a `btf fit` child process. Fit s: the fit alone (fitInfo.seconds, "
          "saved in the fitted file); process s: the whole child (load, fit, save, error); peak "
          "memory: the child's maximum resident set (wait4 rusage). Reused fits show the "
          "figures of the run that made them.\n\n"
       << "| method | fit s | process s | peak memory | reused | file | log |\n"
       << "|---|---|---|---|---|---|---|\n";
    for (const MethodResult& m : r.methods) {
        const std::string log = "fits/" + m.method + ".log";
        md << "| " << m.label() << " | ";
        if (!m.file.empty()) {
            md << "given file, not fitted | | | | " << cell(m.file) << " | |\n";
            continue;
        }
        if (m.failed && !m.fit.ok) {
            md << cell(m.failure) << " | " << fixed(m.fit.wallSeconds, 2) << " | "
               << formatBytes(m.fit.peakRssBytes) << " | no | | [log](" << log << ") |\n";
            continue;
        }
        md << (m.fitSeconds >= 0 ? fixed(m.fitSeconds, 2) : (m.failed ? cell(m.failure) : "n/a"))
           << " | " << fixed(m.fit.wallSeconds, 2) << " | " << formatBytes(m.fit.peakRssBytes)
           << " | " << (m.fit.reused ? "yes" : "no") << " | [" << m.fittedFile << "]("
           << m.fittedFile << ") | [log](" << log << ") |\n";
    }

    md << "\n## Pictures\n\n";
    if (!r.labelsDrawn)
        md << "(No font was found for labels inside the pictures: the column order is in each "
              "caption.)\n\n";
    for (const ComparePicture& p : r.pictures)
        md << "![" << p.file << "](" << p.file << ")\n\n" << p.caption << "\n\n";
    md << "## Recommendation\n\n" << r.recommendation << ".\n";
    return md.str();
}

std::string resultsCsv(const CompareResult& r) {
    std::ostringstream csv;
    std::string passColumns;
    for (const PassTarget& t : r.pass.targets) {
        std::string n = t.name;
        for (char& c : n) c = char(std::tolower(static_cast<unsigned char>(c)));
        passColumns += n + "_ms," + n + "_empty_ms," + n + "_shading_ms," + n + "_floor_ms," + n +
                       "_floor_ratio,";
    }
    csv << "method,status,message,options,error_avg,error_min,error_max,rmse,psnr_db,"
           "nonfinite_values,gpu_cpu_max_diff,values_per_texel,bytes_per_texel,total_bytes,"
           "shared_bytes,compression_ratio,alu_fixed,tex_fixed,alu_per_light,tex_per_light,alu_"
           "total,"
           "tex_total,pass_clock,"
        << passColumns
        << "fit_seconds,fit_process_seconds,peak_rss_bytes,reused,fitted_file,heldout_avg,"
           "heldout_rmse,heldout_psnr_db,heldout_ssim\n";
    for (const MethodResult& m : r.methods) {
        csv << csvField(m.label()) << "," << (m.failed ? "failed" : "ok") << ","
            << csvField(m.failed ? m.failure : "") << "," << csvField(optionText(m)) << ",";
        if (m.failed) {
            // Empty measures (error_avg .. fit_seconds), then what the failed child reported.
            csv << std::string(20 + 5 * r.pass.targets.size(), ',')
                << (m.fit.ok ? "" : full(m.fit.wallSeconds)) << ","
                << (m.fit.ok ? "" : std::to_string(m.fit.peakRssBytes)) << ",,,,,,\n";
            continue;
        }
        const auto optional = [](double v) { return v >= 0 ? full(v) : std::string(); };
        csv << full(m.error.average) << "," << full(m.error.minimum) << "," << full(m.error.maximum)
            << "," << full(m.error.rmse) << "," << full(m.error.psnr) << ","
            << m.error.nonFiniteValues << "," << optional(m.gpuCpuMaxDifference) << ","
            << full(m.memory.valuesPerTexel) << "," << full(m.memory.bytesPerTexel) << ","
            << m.memory.totalBytes << "," << m.memory.sharedBytes << "," << full(m.compressionRatio)
            << ",";
        if (m.cost.counted)
            csv << m.cost.fixedAlu << "," << m.cost.fixedTex << "," << m.cost.perLightAlu << ","
                << m.cost.perLightTex << "," << m.cost.alu(r.pass.lights) << ","
                << m.cost.tex(r.pass.lights) << ",";
        else
            csv << ",,,,,,";
        const MethodPass* primary = m.primaryPass();
        csv << (primary ? primary->pass.clock : std::string()) << ",";
        for (std::size_t i = 0; i < r.pass.targets.size(); ++i) {
            const MethodPass* p =
                i < m.passes.size() && m.passes[i].measured() ? &m.passes[i] : nullptr;
            if (!p) {
                csv << ",,,,,";
                continue;
            }
            // The shading time and its ratio may be negative (noise): written as measured.
            csv << full(p->pass.ms) << "," << full(p->emptyMs) << "," << full(p->shadingMs) << ","
                << optional(p->floorMs) << "," << (p->floorMs > 0 ? full(p->floorRatio) : "")
                << ",";
        }
        csv << optional(m.fitSeconds) << "," << full(m.fit.wallSeconds) << "," << m.fit.peakRssBytes
            << "," << (m.fit.reused ? "yes" : "no") << "," << csvField(m.fittedFile);
        if (m.heldOutScored())
            csv << "," << full(m.heldOut.error.average) << "," << full(m.heldOut.error.rmse) << ","
                << full(m.heldOut.error.psnr) << "," << full(m.heldOut.ssim) << "\n";
        else
            csv << ",,,,\n";
    }
    return csv.str();
}

std::string resultsJson(const CompareResult& r) {
    nlohmann::json j;
    j["input"] = {{"path", r.input},
                  {"width", r.width},
                  {"height", r.height},
                  {"views", r.views},
                  {"lights", r.lights},
                  {"error_texels", r.errorTexels},
                  {"raw_bytes_per_texel", r.rawBytesPerTexel},
                  {"raw_total_bytes", r.rawTotalBytes}};
    j["held_out"] = {{"fraction", r.holdoutFraction}, {"note", r.holdoutNote}};
    j["gpu"] = {{"ran", r.gpuRan},
                {"note", r.gpuNote},
                {"renderer", r.glRenderer},
                {"version", r.glVersion},
                {"software", r.softwareRenderer}};
    j["pass"] = {{"width", r.pass.width},
                 {"height", r.pass.height},
                 {"lights", r.pass.lights},
                 {"frames", r.pass.frames},
                 {"warmup_frames", r.pass.warmupFrames},
                 {"texture_scale", r.pass.textureScale}};
    nlohmann::json targetNames = nlohmann::json::array();
    for (const PassTarget& t : r.pass.targets) targetNames.push_back(t.name);
    j["pass"]["targets"] = targetNames;
    if (r.gpuRan) {
        nlohmann::json calibrations = nlohmann::json::array();
        for (const Calibration& c : r.calibrations)
            calibrations.push_back({{"target", c.target.name},
                                    {"fetches_per_pixel", c.fetchCount},
                                    {"empty_ms", c.empty.ms},
                                    {"fetch_ms", c.fetches.ms},
                                    {"fetches_per_second", c.fetchesPerSecond},
                                    {"clock", c.fetches.clock}});
        j["calibrations"] = calibrations;
    }
    nlohmann::json pairs = nlohmann::json::array();
    for (const auto& [v, l] : r.spotCheckPairs) pairs.push_back({{"view", v}, {"light", l}});
    j["spot_check_pairs"] = pairs;
    nlohmann::json methods = nlohmann::json::array();
    for (const MethodResult& m : r.methods) {
        nlohmann::json e{
            {"method", m.method}, {"options", m.options}, {"status", m.failed ? "failed" : "ok"}};
        if (!m.file.empty()) {
            e["label"] = m.label();
            e["file"] = m.file;  // given, not fitted: "fit" holds zeros
        }
        if (m.failed) e["message"] = m.failure;
        e["fit"] = {{"process_seconds", m.fit.wallSeconds},
                    {"peak_rss_bytes", m.fit.peakRssBytes},
                    {"reused", m.fit.reused}};
        if (!m.failed) {
            e["fitted_file"] = m.fittedFile;
            if (m.heldOutScored())
                e["held_out"] = {{"fitted_file", m.heldOutFile},
                                 {"average", number(m.heldOut.error.average)},
                                 {"rmse", number(m.heldOut.error.rmse)},
                                 {"psnr_db", number(m.heldOut.error.psnr)},
                                 {"ssim", number(m.heldOut.ssim)},
                                 {"pairs", m.heldOut.pairs},
                                 {"images_scored", m.heldOut.imagesScored},
                                 {"fit_seconds", number(m.heldOutFitSeconds)}};
            else if (!m.heldOutFailure.empty())
                e["held_out"] = {{"failure", m.heldOutFailure}};
            e["fit"]["seconds"] = number(m.fitSeconds);
            e["error"] = {{"average", number(m.error.average)},
                          {"minimum", number(m.error.minimum)},
                          {"maximum", number(m.error.maximum)},
                          {"rmse", number(m.error.rmse)},
                          {"psnr_db", number(m.error.psnr)},
                          {"nonfinite_values", m.error.nonFiniteValues}};
            if (m.gpuCpuMaxDifference >= 0) e["error"]["gpu_cpu_max_diff"] = m.gpuCpuMaxDifference;
            e["memory"] = {{"values_per_texel", m.memory.valuesPerTexel},
                           {"bytes_per_texel", m.memory.bytesPerTexel},
                           {"total_bytes", m.memory.totalBytes},
                           {"shared_bytes", m.memory.sharedBytes},
                           {"compression_ratio", m.compressionRatio}};
            nlohmann::json pass{{"counted", m.cost.counted}, {"rule", m.cost.formula}};
            if (m.cost.counted) {
                pass["alu_fixed"] = m.cost.fixedAlu;
                pass["tex_fixed"] = m.cost.fixedTex;
                pass["alu_per_light"] = m.cost.perLightAlu;
                pass["tex_per_light"] = m.cost.perLightTex;
                pass["alu_total"] = m.cost.alu(r.pass.lights);
                pass["tex_total"] = m.cost.tex(r.pass.lights);
            }
            nlohmann::json times = nlohmann::json::array();
            for (const MethodPass& p : m.passes) {
                nlohmann::json t{{"target", p.target.name}};
                if (p.measured()) {
                    t["ms"] = p.pass.ms;
                    t["clock"] = p.pass.clock;
                    t["empty_ms"] = p.emptyMs;
                    t["shading_ms"] = p.shadingMs;
                    t["wall_ms"] = p.pass.timing.wallMs;
                    t["cpu_ms"] = p.pass.timing.cpuMs;
                    t["gpu_timer_ms"] = p.pass.timing.gpuMs;
                    if (p.floorMs > 0) {
                        t["floor_ms"] = p.floorMs;
                        t["floor_ratio"] = p.floorRatio;
                    }
                }
                times.push_back(t);
            }
            pass["targets"] = times;
            e["pass"] = pass;
        }
        methods.push_back(e);
    }
    j["methods"] = methods;
    nlohmann::json pictures = nlohmann::json::array();
    for (const ComparePicture& p : r.pictures)
        pictures.push_back({{"file", p.file}, {"caption", p.caption}});
    j["pictures"] = pictures;
    j["error_map_max"] = r.errorMapMax;
    j["recommendation"] = {{"method", r.recommended},
                           {"text", r.recommendation},
                           {"max_bytes_per_texel", r.maxBytesPerTexel},
                           {"max_ms_per_pass", r.maxMsPerPass}};
    return j.dump(2) + "\n";
}

}  // namespace osgBTF

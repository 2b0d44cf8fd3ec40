#include "harness/Compare.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/Progress.h"
#include "core/PublishFolder.h"
#include "harness/FitScore.h"
#include "harness/MaterialImage.h"
#include "harness/Pictures.h"
#include "harness/Report.h"
#include "loaders/LoadBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "scene/EnvironmentLight.h"

namespace osgBTF {

namespace fs = std::filesystem;

std::vector<std::string> allCompareMethods() {
    std::vector<std::string> methods;
    for (const std::string& name : methodNamesInOrder())
        if (findMethod(name).compareAll) methods.push_back(name);
    return methods;
}

std::string MethodResult::label() const {
    if (file.empty()) return method;
    const fs::path path(file);
    const fs::path folder = path.parent_path().filename();
    return "file:" + (path.filename() == "info.json" && !folder.empty()
                          ? (folder / path.filename()).generic_string()
                          : path.filename().string());
}

namespace {

std::string formatNumber(double value, int precision) {
    std::ostringstream out;
    out << std::setprecision(precision) << value;
    return out.str();
}

std::vector<std::string> orderedMethods(const CompareOptions& options) {
    std::vector<std::string> methods{baselineMethod().name};
    for (const std::string& m : options.methods) {
        findMethod(m);  // throws "unknown method 'x' (known: ...)"
        if (std::find(methods.begin(), methods.end(), m) == methods.end()) methods.push_back(m);
    }
    for (const auto& entry : options.methodOptions)
        if (std::find(methods.begin(), methods.end(), entry.first) == methods.end())
            throw Error("options given for method '" + entry.first +
                        "', which is not among the compared methods");
    return methods;
}

/** Measured (view, light) pairs shown in the grids and used for the GPU spot check. */
std::vector<std::pair<std::size_t, std::size_t>> spotPairs(const BtfSource& btf) {
    const float wanted[][4] = {{0, 0, 45, 0}, {45, 90, 60, 180}, {60, 0, 30, 270}};
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    for (const auto& w : wanted) {
        const auto pair = std::make_pair(nearestDirection(btf.views(), w[0], w[1]),
                                         nearestDirection(btf.lights(), w[2], w[3]));
        if (std::find(pairs.begin(), pairs.end(), pair) == pairs.end()) pairs.push_back(pair);
    }
    return pairs;
}

std::string pairName(const BtfSource& btf, const std::pair<std::size_t, std::size_t>& p) {
    const Direction& v = btf.views()[p.first];
    const Direction& l = btf.lights()[p.second];
    return "view " + formatNumber(v.theta, 3) + "," + formatNumber(v.phi, 3) + " light " +
           formatNumber(l.theta, 3) + "," + formatNumber(l.phi, 3);
}

/** Column labels above a row of tiles; returns false if no font is available. */
bool labelColumns(FloatImage& image, const std::vector<std::string>& labels, int cellWidth, int gap,
                  int bandHeight, float textValue = 1.0f) {
    bool drawn = true;
    for (std::size_t i = 0; i < labels.size(); ++i)
        drawn &= drawText(image, int(i) * (cellWidth + gap) + 3, bandHeight - 6, labels[i],
                          std::max(10, bandHeight - 8), textValue);
    return drawn;
}

/** Runs (or reuses) one `btf fit` child; false when it failed. */
bool fitOrReuse(const CompareOptions& options, const fs::path& work, FitJob& job,
                const std::string& file, FitProcessResult& result) {
    const std::string stem = file.substr(0, file.rfind('.'));
    job.output = (work / file).string();
    job.log = (work / (stem + ".log")).string();
    const fs::path previous = fs::path(options.outputDir) / file;
    if (options.reuseFits && canReuseFit(job, previous.string(), result)) {
        fs::copy_file(previous, job.output);
        // Same fit, same age: a later run still sees it as newer than INPUT.
        fs::last_write_time(job.output, fs::last_write_time(previous));
        fs::copy_file(previous.string() + ".json", job.output + ".json");
        std::error_code ec;  // the log is nice to have
        fs::copy_file(fs::path(options.outputDir) / (stem + ".log"), job.log, ec);
    } else {
        result = runFitProcess(job);
        if (result.ok) writeFitRecord(job, result, job.output + ".json");
    }
    return result.ok;
}

void fitStage(const CompareOptions& options, const fs::path& work, CompareResult& result) {
    const std::string tool = options.fitTool.empty() ? defaultFitTool() : options.fitTool;
    const bool heldOut = result.holdoutFraction > 0;
    const std::size_t fitted =
        std::size_t(std::count_if(result.methods.begin(), result.methods.end(),
                                  [](const MethodResult& m) { return m.file.empty(); }));
    Progress progress(heldOut ? "fitting, and fitting without the held-out pairs (child processes)"
                              : "fitting (child processes)",
                      fitted * (heldOut ? 2 : 1));
    for (MethodResult& m : result.methods) {
        if (!m.file.empty()) continue;  // a given file: nothing to fit
        FitJob job;
        job.tool = tool;
        job.input = options.input;
        job.method = m.method;
        job.options = m.options;
        job.extraArguments = options.fitExtraArguments;
        job.globalArguments = options.fitGlobalArguments;
        m.fittedFile = "fits/" + m.method + ".exr";
        if (!fitOrReuse(options, work, job, m.fittedFile, m.fit)) {
            m.failed = true;
            m.failure = "failed: " + m.fit.message;
        }
        progress.advance();
        if (!heldOut) continue;
        if (!m.failed) {
            job.extraArguments.insert(
                job.extraArguments.end(),
                {"--holdout-fraction", formatNumber(result.holdoutFraction, 6)});
            m.heldOutFile = "fits/" + m.method + "-heldout.exr";
            try {
                if (!fitOrReuse(options, work, job, m.heldOutFile, m.heldOutFit))
                    m.heldOutFailure = "failed: " + m.heldOutFit.message;
            } catch (const Error& e) {  // the child could not start: the method's row stands
                m.heldOutFailure = std::string("failed: ") + e.what();
            }
        }
        progress.advance();
    }
}

/** A material at every measured (view, light) pair of `btf`, in MeasuredBtf::abrdf's layout
 *  ([view][light][rgb]): for a file fitted elsewhere, whose own measured directions (none, or a
 *  relight file's lights) are not the BTF's. */
void evaluateAtMeasured(const Material& material, const BtfSource& btf, std::size_t texel,
                        float* out) {
    const int x = int(texel % std::size_t(btf.width())), y = int(texel / std::size_t(btf.width()));
    for (std::size_t v = 0; v < btf.viewCount(); ++v) {
        const glm::vec3 view = btf.views().vector(v);
        for (std::size_t l = 0; l < btf.lightCount(); ++l) {
            const glm::vec3 value = material.evaluate(x, y, view, btf.lights().vector(l));
            *out++ = value.r;
            *out++ = value.g;
            *out++ = value.b;
        }
    }
}

void errorStage(const BtfSource& btf, const fs::path& work, CompareResult& result,
                std::vector<osg::ref_ptr<Material>>& materials) {
    Progress progress("error and memory tables (CPU)", result.methods.size());
    // The same texels for every method, so that their errors compare.
    const std::vector<std::size_t> subsample =
        errorSubsample(btf, static_cast<long long>(result.errorTexels));
    const batch::HoldoutSplit split =
        result.holdoutFraction > 0
            ? batch::holdoutSplit(btf.viewCount(), btf.lightCount(), result.holdoutFraction)
            : batch::HoldoutSplit();
    materials.assign(result.methods.size(), nullptr);
    for (std::size_t i = 0; i < result.methods.size(); ++i) {
        MethodResult& m = result.methods[i];
        if (!m.failed && !m.file.empty()) {
            // A given file: evaluated at the BTF's measured directions, not at its own.
            try {
                osg::ref_ptr<Material> material = loadMaterial(m.file);
                m.method = material->methodName();
                m.fittedFile = m.file;
                if (material->width() != btf.width() || material->height() != btf.height())
                    throw Error(m.file + ": " + std::to_string(material->width()) + "x" +
                                std::to_string(material->height()) + " texels, the BTF has " +
                                std::to_string(btf.width()) + "x" + std::to_string(btf.height()));
                m.error = computeError(
                    btf,
                    [&](std::size_t texel, float* out) {
                        evaluateAtMeasured(*material, btf, texel, out);
                    },
                    subsample.empty() ? nullptr : &subsample);
                m.memory = material->memory();
                if (m.memory.bytesPerTexel > 0)
                    m.compressionRatio = result.rawBytesPerTexel / m.memory.bytesPerTexel;
                m.cost = shaderCost(*material);
                materials[i] = material;
            } catch (const std::exception& e) {
                m.failed = true;
                m.failure = std::string("failed: ") + e.what();
            }
        } else if (!m.failed) {
            try {
                osg::ref_ptr<Material> material = loadMaterial((work / m.fittedFile).string());
                if (material->width() != btf.width() || material->height() != btf.height())
                    throw Error(m.fittedFile + ": fitted to a different size");
                const FitScore score = scoreFit(btf, *material, subsample);
                m.error = score.error;
                m.memory = score.memory;
                if (m.memory.bytesPerTexel > 0) m.compressionRatio = score.compressionRatio;
                m.cost = shaderCost(*material);
                const auto seconds = material->fitInfo.find("seconds");
                if (seconds != material->fitInfo.end()) m.fitSeconds = std::stod(seconds->second);
                materials[i] = material;
            } catch (const std::exception& e) {
                m.failed = true;
                m.failure = std::string("failed: ") + e.what();
            }
        }
        if (!m.failed && m.heldOutScored()) {
            try {
                const osg::ref_ptr<Material> without =
                    loadMaterial((work / m.heldOutFile).string());
                m.heldOut =
                    scoreHeldOut(btf, *without, split, subsample.empty() ? nullptr : &subsample);
                const auto seconds = without->fitInfo.find("seconds");
                if (seconds != without->fitInfo.end())
                    m.heldOutFitSeconds = std::stod(seconds->second);
            } catch (const std::exception& e) {
                m.heldOutFailure = std::string("failed: ") + e.what();
            }
        }
        progress.advance();
    }
}

/** pictures/environment.png: the sample patch lit by options.envFile, a column per method, a row
 *  per view (harness/MaterialImage.h: renderEnvironmentImage). */
void environmentPicture(const CompareOptions& options, HeadlessRenderer& renderer,
                        const fs::path& work, CompareResult& result,
                        const std::vector<osg::ref_ptr<Material>>& materials) {
    osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
    light->setFile(options.envFile);
    if (!light->hasMap()) throw Error("--env: " + light->getError());
    light->setRotation(options.envRotation);
    const EnvironmentMap map = light->projectionMap();
    const Direction views[] = {{0.0f, 0.0f}, {60.0f, 0.0f}};
    Progress progress("environment renders", std::size(views) * materials.size());
    std::vector<std::vector<FloatImage>> rows(std::size(views));
    std::vector<std::string> labels;
    int cell = 0;
    for (std::size_t i = 0; i < materials.size(); ++i) {
        if (!materials[i]) continue;
        labels.push_back(result.methods[i].label());
        const std::vector<glm::vec3> g = projectPatchEnvironment(*materials[i], map);
        const int factor = std::max(1, 128 / std::max(1, materials[i]->width()));
        for (std::size_t v = 0; v < std::size(views); ++v) {
            rows[v].push_back(
                enlarge(renderEnvironmentImage(renderer, *materials[i], g, views[v].toVector(),
                                               options.envExposure),
                        factor));
            cell = std::max(cell, rows[v].back().width);
            progress.advance();
        }
    }
    constexpr int kGap = 4, kBand = 22;
    FloatImage sheet = addTopBand(tileImages(rows, kGap, 0.0f), kBand, 0.0f);
    result.labelsDrawn &= labelColumns(sheet, labels, cell, kGap, kBand);
    writeFloatImage(sheet, (work / "pictures/environment.png").string(), false, true);
    result.pictures.push_back(
        {"pictures/environment.png",
         "The sample patch (normal +Z, nothing occluding it) lit by the environment " +
             fs::path(options.envFile).filename().string() + " (rotation " +
             formatNumber(options.envRotation, 3) + " degrees, exposure " +
             formatNumber(options.envExposure, 3) +
             "), one column per method, rows: view from above, view 60 degrees from +X. " +
             environmentMethodsText() +
             " through their folded environment programs (exact); the others as the sum "
             "of their point-light images at the measured light directions weighted by the "
             "projected environment (scene/README.md). sRGB-encoded preview of linear values."});
}

void gpuStage(const CompareOptions& options, const BtfSource& btf, const fs::path& work,
              CompareResult& result, const std::vector<osg::ref_ptr<Material>>& materials) {
    std::unique_ptr<HeadlessRenderer> renderer;
    try {
        renderer = std::make_unique<HeadlessRenderer>();
    } catch (const Error& e) {
        result.gpuNote = std::string("no headless OpenGL context: ") + e.what();
        return;
    }
    result.gpuRan = true;
    result.glRenderer = renderer->glRenderer();
    result.glVersion = renderer->glVersion();
    result.softwareRenderer = renderer->isSoftwareRenderer();
    result.gpuNote = "rendered with " + result.glRenderer + " (" + result.glVersion + ")";

    {
        Progress progress("GPU spot check", materials.size());
        for (std::size_t i = 0; i < materials.size(); ++i) {
            if (materials[i]) try {
                    double worst = 0;
                    for (const auto& [v, l] : result.spotCheckPairs) {
                        const glm::vec3 view = btf.views().vector(v),
                                        light = btf.lights().vector(l);
                        worst = std::max(
                            worst, maxAbsDifference(
                                       renderMaterialImage(*renderer, *materials[i], view, light),
                                       evaluateMaterialImage(*materials[i], view, light)));
                    }
                    result.methods[i].gpuCpuMaxDifference = worst;
                } catch (const Error& e) {
                    // One method's GPU trouble must not cost the others their results.
                    result.gpuNote += "; " + result.methods[i].label() + " GPU check: " + e.what();
                }
            progress.advance();
        }
    }
    {
        const std::vector<PassTarget>& targets = options.pass.targets;
        Progress progress("pass timing", targets.size() * (materials.size() + 1));
        for (const PassTarget& target : targets) {
            // Per target: its empty and calibration passes first, then every method, so each
            // method is set against passes of the same run and target.
            result.calibrations.push_back(runCalibration(*renderer, options.pass, target));
            progress.advance();
            for (std::size_t i = 0; i < materials.size(); ++i) {
                if (materials[i]) try {
                        MethodResult& m = result.methods[i];
                        m.passes.push_back(timeMethodPass(
                            *renderer, *materials[i], options.pass, result.calibrations.back(),
                            m.cost.counted ? m.cost.tex(options.pass.lights) : -1));
                    } catch (const Error& e) {
                        result.gpuNote += "; " + result.methods[i].label() + " pass timing (" +
                                          target.name + "): " + e.what();
                        MethodPass unmeasured;  // keeps passes aligned with the calibrations
                        unmeasured.target = target;
                        result.methods[i].passes.push_back(unmeasured);
                    }
                progress.advance();
            }
        }
    }
    {
        const std::vector<SphereSetting> settings = defaultSphereSettings();
        Progress progress("model renders", settings.size() * materials.size());
        std::vector<std::vector<FloatImage>> rows;
        std::vector<std::string> labels;
        for (std::size_t i = 0; i < materials.size(); ++i)
            if (materials[i]) labels.push_back(result.methods[i].label());
        for (const SphereSetting& setting : settings) {
            std::vector<FloatImage> row;
            for (const auto& material : materials) {
                if (material)
                    row.push_back(renderSphere(*renderer, *material, setting, options.sphereSize,
                                               options.sphereTextureScale));
                progress.advance();
            }
            rows.push_back(std::move(row));
        }
        constexpr int kGap = 4, kBand = 22;
        FloatImage sheet = addTopBand(tileImages(rows, kGap, 0.0f), kBand, 0.0f);
        result.labelsDrawn &= labelColumns(sheet, labels, options.sphereSize, kGap, kBand);
        writeFloatImage(sheet, (work / "pictures/spheres.png").string(), false, true);
        std::string caption = "Sphere rendered with every method (columns: ";
        for (std::size_t i = 0; i < labels.size(); ++i) caption += (i ? ", " : "") + labels[i];
        caption += "; " + baselineMethod().name + " is the plain lit texture baseline). Rows: ";
        for (std::size_t i = 0; i < settings.size(); ++i)
            caption += (i ? ", " : "") + settings[i].name;
        caption += ". sRGB-encoded preview of linear values, texture repeated " +
                   formatNumber(options.sphereTextureScale, 3) + " times.";
        result.pictures.push_back({"pictures/spheres.png", caption});
    }
    if (!options.envFile.empty()) environmentPicture(options, *renderer, work, result, materials);
}

void pictureStage(const BtfSource& btf, const fs::path& work, CompareResult& result,
                  const std::vector<osg::ref_ptr<Material>>& materials) {
    Progress progress("pictures", 3);
    std::vector<std::string> labels;
    for (std::size_t i = 0; i < materials.size(); ++i)
        if (materials[i]) labels.push_back(result.methods[i].label());
    const int factor = std::max(1, int(std::ceil(128.0 / std::max(btf.width(), 1))));
    const int cell = btf.width() * factor;
    constexpr int kGap = 4, kBand = 22;
    bool labelsDrawn = true;

    // Error maps, one colour scale for all methods.
    result.errorMapMax = 0;
    for (std::size_t i = 0; i < materials.size(); ++i)
        if (materials[i] && std::isfinite(result.methods[i].error.maximum))
            result.errorMapMax = std::max(result.errorMapMax, result.methods[i].error.maximum);
    {
        std::vector<FloatImage> maps;
        for (std::size_t i = 0; i < materials.size(); ++i)
            if (materials[i])
                maps.push_back(
                    enlarge(colourMappedErrors(result.methods[i].error.perTexel, btf.width(),
                                               btf.height(), result.errorMapMax),
                            factor));
        if (!maps.empty()) {
            FloatImage sheet = addTopBand(tileImages({maps}, kGap, 1.0f), kBand, 1.0f);
            labelsDrawn &= labelColumns(sheet, labels, cell, kGap, kBand, 0.0f);
            // Legend: a colour bar under the maps with its end values.
            const int barWidth = std::min(sheet.width, 256);
            FloatImage legend(std::max(sheet.width, barWidth), 40, 3);
            std::fill(legend.pixels.begin(), legend.pixels.end(), 1.0f);
            const FloatImage bar = colourBar(barWidth, 14);
            for (int y = 0; y < bar.height; ++y)
                for (int x = 0; x < bar.width; ++x)
                    for (int c = 0; c < 3; ++c) legend.at(x, 4 + y, c) = bar.at(x, y, c);
            labelsDrawn &= drawText(legend, 0, 36, "0", 12, 0.0f);
            labelsDrawn &= drawText(legend, std::max(0, barWidth - 60), 36,
                                    formatNumber(result.errorMapMax, 3), 12, 0.0f);
            sheet = stackImages(sheet, legend, 2, 1.0f);
            writeFloatImage(sheet, (work / "pictures/error-maps.png").string());
            result.pictures.push_back(
                {"pictures/error-maps.png",
                 "Per-texel error (Meseth et al. 2003, sec. 4.1) of each method, viridis colour "
                 "map from 0 "
                 "(dark blue) to " +
                     formatNumber(result.errorMapMax, 4) +
                     " (yellow, the largest per-texel error of all methods); magenta = NaN/Inf. "
                     "Columns: " +
                     [&] {
                         std::string s;
                         for (std::size_t i = 0; i < labels.size(); ++i)
                             s += (i ? ", " : "") + labels[i];
                         return s;
                     }() +
                     "; each texel enlarged " + std::to_string(factor) + "x."});
        }
    }
    progress.advance();

    // Measured vs modelled for the spot-check pairs.
    {
        std::vector<std::vector<FloatImage>> rows;
        std::string rowNames;
        for (const auto& pair : result.spotCheckPairs) {
            const glm::vec3 view = btf.views().vector(pair.first);
            const glm::vec3 light = btf.lights().vector(pair.second);
            std::vector<FloatImage> row{
                enlarge(measuredImage(btf, pair.first, pair.second), factor)};
            for (const auto& material : materials)
                if (material)
                    row.push_back(enlarge(evaluateMaterialImage(*material, view, light), factor));
            rows.push_back(std::move(row));
            rowNames += (rowNames.empty() ? "" : "; ") + pairName(btf, pair);
        }
        std::vector<std::string> columns{"measured"};
        columns.insert(columns.end(), labels.begin(), labels.end());
        FloatImage sheet = addTopBand(tileImages(rows, kGap, 0.0f), kBand, 0.0f);
        labelsDrawn &= labelColumns(sheet, columns, cell, kGap, kBand);
        writeFloatImage(sheet, (work / "pictures/measured-vs-model.png").string(), false, true);
        std::string columnNames;
        for (std::size_t i = 0; i < columns.size(); ++i)
            columnNames += (i ? ", " : "") + columns[i];
        result.pictures.push_back(
            {"pictures/measured-vs-model.png",
             "Measured images and each model (CPU evaluator) at measured (view, light) pairs. "
             "Columns: " +
                 columnNames + ". Rows: " + rowNames + " (theta,phi degrees). sRGB-encoded."});
    }
    progress.advance();

    std::vector<PlotPoint> points;
    for (const MethodResult& m : result.methods)
        if (!m.failed) points.push_back({m.label(), m.memory.bytesPerTexel, m.error.average});
    writeTextAtomically(
        (work / "pictures/error-vs-memory.svg").string(),
        errorMemorySvg(points, "Error vs memory: " + fs::path(result.input).filename().string()));
    result.pictures.push_back({"pictures/error-vs-memory.svg",
                               "Average per-texel error against bytes per texel (log scale)."});
    progress.advance();
    result.labelsDrawn = result.labelsDrawn && labelsDrawn;
}

}  // namespace

void recommend(CompareResult& result) {
    const MethodResult* best = nullptr;
    for (const MethodResult& m : result.methods) {
        if (m.failed || !m.file.empty()) continue;  // given files are references, not choices
        if (result.maxBytesPerTexel > 0 && m.memory.bytesPerTexel > result.maxBytesPerTexel)
            continue;
        const MethodPass* pass = m.primaryPass();
        if (result.maxMsPerPass > 0 && !(pass && pass->pass.ms <= result.maxMsPerPass)) continue;
        if (!best || m.error.average < best->error.average) best = &m;
    }
    std::string budgets;
    if (result.maxBytesPerTexel > 0)
        budgets += "at most " + formatNumber(result.maxBytesPerTexel, 6) + " bytes per texel";
    if (result.maxMsPerPass > 0)
        budgets += std::string(budgets.empty() ? "" : " and ") + "at most " +
                   formatNumber(result.maxMsPerPass, 6) + " ms per pass (" +
                   (result.pass.targets.empty() ? std::string()
                                                : result.pass.targets.front().name + ", ") +
                   std::to_string(result.pass.width) + "x" + std::to_string(result.pass.height) +
                   ", " + std::to_string(result.pass.lights) + " light" +
                   (result.pass.lights == 1 ? "" : "s") + ")";
    if (budgets.empty()) budgets = "no budget given";
    if (best) {
        result.recommended = best->method;
        result.recommendation = "Recommendation: " + best->method +
                                " (lowest average per-texel error, " +
                                formatNumber(best->error.average, 5) + ", within " + budgets + ")";
    } else {
        result.recommended.clear();
        result.recommendation =
            "Recommendation: none; no completed method fits the budgets (" + budgets + ")";
    }
}

CompareResult runCompare(const CompareOptions& options) {
    const std::vector<std::string> methods = orderedMethods(options);
    if (options.outputDir.empty()) throw Error("no output folder given");
    // Loading first: a bad INPUT stops here, before any folder is created.
    // A UBO2014 file stays factored (decoded block by block where read), so full-size files fit.
    const std::unique_ptr<BtfSource> input = openBtfSource(options.input, options.load);
    const BtfSource& btf = *input;

    CompareResult result;
    result.input = options.input;
    result.width = btf.width();
    result.height = btf.height();
    result.views = btf.viewCount();
    result.lights = btf.lightCount();
    result.rawBytesPerTexel = double(btf.viewCount() * btf.lightCount() * 3);
    result.rawTotalBytes = std::uint64_t(btf.texelCount()) * btf.viewCount() * btf.lightCount() * 3;
    result.pass = options.pass;
    result.maxBytesPerTexel = options.maxBytesPerTexel;
    result.maxMsPerPass = options.maxMsPerPass;
    result.spotCheckPairs = spotPairs(btf);
    result.errorTexels = errorTexelCount(btf, options.errorTexels);
    if (options.holdoutFraction > 0) {
        try {
            const batch::HoldoutSplit split =
                batch::holdoutSplit(btf.viewCount(), btf.lightCount(), options.holdoutFraction);
            result.holdoutFraction = options.holdoutFraction;
            result.holdoutNote = std::to_string(split.leftOutPairs.size()) + " of " +
                                 std::to_string(btf.imageCount()) + " (view, light) pairs: " +
                                 std::to_string(btf.viewCount() - split.keptViews.size()) + " of " +
                                 std::to_string(btf.viewCount()) + " views and " +
                                 std::to_string(btf.lightCount() - split.keptLights.size()) +
                                 " of " + std::to_string(btf.lightCount()) + " lights left out";
        } catch (const Error& e) {
            result.holdoutNote = std::string("no held-out fits: ") + e.what();
        }
    } else {
        result.holdoutNote = "no held-out fits (--holdout-fraction 0)";
    }
    result.labelsDrawn = true;  // until a label fails to draw
    for (const std::string& name : methods) {
        MethodResult m;
        m.method = name;
        const auto it = options.methodOptions.find(name);
        if (it != options.methodOptions.end()) m.options = it->second;
        result.methods.push_back(std::move(m));
    }
    for (const std::string& file : options.materialFiles) {
        MethodResult m;
        m.file = file;
        result.methods.push_back(std::move(m));
    }

    const fs::path target = fs::absolute(options.outputDir).lexically_normal();
    const fs::path parent =
        target.has_filename() ? target.parent_path() : target.parent_path().parent_path();
    const fs::path finalTarget = target.has_filename() ? target : target.parent_path();
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec) throw Error(parent.string() + ": cannot create the folder: " + ec.message());
    // Work folders of earlier runs that were killed (a dead process's DIR.tmp<pid>, DIR.old<pid>).
    removeStaleTemporaries(parent.string(), [&](const std::string& stem) {
        return stem == finalTarget.filename().string();
    });
    fs::path work = parent / (finalTarget.filename().string() + ".tmp" + std::to_string(getpid()));
    fs::remove_all(work, ec);
    fs::create_directories(work / "fits", ec);
    if (!ec) fs::create_directories(work / "pictures", ec);
    if (ec) throw Error(work.string() + ": cannot create the folder: " + ec.message());
    try {
        CompareOptions effective = options;
        effective.outputDir = finalTarget.string();
        fitStage(effective, work, result);
        std::vector<osg::ref_ptr<Material>> materials;
        errorStage(btf, work, result, materials);
        if (options.gpu)
            gpuStage(options, btf, work, result, materials);
        else
            result.gpuNote = "GPU part skipped (--no-gpu)";
        pictureStage(btf, work, result, materials);
        recommend(result);
        writeTextAtomically((work / "report.md").string(), reportMarkdown(result));
        writeTextAtomically((work / "results.csv").string(), resultsCsv(result));
        writeTextAtomically((work / "results.json").string(), resultsJson(result));
        publishFolder(work, finalTarget);
    } catch (...) {
        fs::remove_all(work, ec);
        throw;
    }
    return result;
}

}  // namespace osgBTF

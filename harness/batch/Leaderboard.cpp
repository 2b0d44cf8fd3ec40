// `btf batch report RESULTS`: every job's result gathered into one leaderboard (report.md,
// results.csv, results.json and index.html, whose page is harness/batch/leaderboard.html).
#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/MeasuredBtf.h"
#include "harness/batch/BatchFiles.h"

namespace osgBTF {
extern const char* const leaderboardPageTemplate;  // generated from harness/batch/leaderboard.html
}

namespace osgBTF::batch {

namespace fs = std::filesystem;

namespace {

struct Row {
    const BatchJob* job;
    const BatchMaterial* material;
    JobResult result;
    bool pareto = false;
    bool done() const { return result.state == JobState::Done; }
};

std::string optionsText(const std::map<std::string, std::string>& options) {
    std::string text;
    for (const auto& [key, value] : options) text += (text.empty() ? "" : " ") + key + "=" + value;
    return text;
}

/** Pareto front of (bytes per texel, average error) among a material's completed jobs: no other
 *  job is at most as large and at most as wrong, and better in one of the two. */
void markPareto(std::vector<Row>& rows) {
    for (Row& row : rows) {
        if (!row.done()) continue;
        row.pareto = true;
        for (const Row& other : rows) {
            if (&other == &row || !other.done() || other.material != row.material) continue;
            const bool noWorse = other.result.bytesPerTexel <= row.result.bytesPerTexel &&
                                 other.result.average <= row.result.average;
            const bool better = other.result.bytesPerTexel < row.result.bytesPerTexel ||
                                other.result.average < row.result.average;
            if (noWorse && better) row.pareto = false;
        }
    }
}

struct ClassChoice {
    std::string name;
    std::size_t materials = 0;
    std::string recommended, reason;
    double score = 0;
};

/** Per class: the method (with its options) of lowest mean held-out error (the average error
 *  where a job has none) among those completed on every material of the class with a
 *  compression ratio above 1 on each (a method storing more than the data is no compression;
 *  on tiny samples the shared tables of pca and lpca are). */
std::vector<ClassChoice> recommendPerClass(const Manifest& manifest, const std::vector<Row>& rows) {
    std::map<std::string, std::set<std::string>> materialsOf;
    for (const BatchMaterial& m : manifest.materials) materialsOf[m.materialClass].insert(m.name);
    std::vector<ClassChoice> choices;
    for (const auto& [name, materials] : materialsOf) {
        ClassChoice choice;
        choice.name = name;
        choice.materials = materials.size();
        // key: method + options -> (materials done, summed score, all held out)
        struct Sum {
            std::size_t count = 0;
            double sum = 0;
            bool heldOut = true;
            bool compresses = true;  ///< smaller than the measured data on every material
        };
        std::map<std::string, Sum> sums;
        for (const Row& row : rows) {
            if (!row.done() || !materials.count(row.material->name)) continue;
            const std::string key =
                row.job->method +
                (row.job->options.empty() ? "" : " " + optionsText(row.job->options));
            Sum& sum = sums[key];
            ++sum.count;
            const bool held = std::isfinite(row.result.heldOutAverage);
            sum.sum += held ? row.result.heldOutAverage : row.result.average;
            sum.heldOut = sum.heldOut && held;
            sum.compresses = sum.compresses && row.result.compressionRatio > 1;
        }
        double best = std::numeric_limits<double>::infinity();
        bool heldOut = false;
        for (const auto& [key, sum] : sums) {
            if (sum.count != materials.size() || !sum.compresses) continue;
            const double mean = sum.sum / double(sum.count);
            if (mean < best) {
                best = mean;
                choice.recommended = key;
                heldOut = sum.heldOut;
            }
        }
        if (choice.recommended.empty()) {
            choice.reason =
                "no method has completed on every material of the class with a compression "
                "ratio above 1";
        } else {
            std::ostringstream reason;
            reason << "lowest mean " << (heldOut ? "held-out " : "") << "average error ("
                   << std::setprecision(4) << best << ") among the methods completed on all "
                   << materials.size() << " material" << (materials.size() == 1 ? "" : "s")
                   << " that store less than the measured data";
            choice.reason = reason.str();
            choice.score = best;
        }
        choices.push_back(choice);
    }
    return choices;
}

std::string cell(double value, int precision) {
    if (!std::isfinite(value)) return "–";
    std::ostringstream out;
    out << std::setprecision(precision) << value;
    return out.str();
}

std::string csvNumber(double value) {
    if (!std::isfinite(value)) return "";
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", value);
    return text;
}

std::string csvText(const std::string& text) {
    if (text.find_first_of(",\"\n") == std::string::npos) return text;
    std::string out = "\"";
    for (const char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
    return out + "\"";
}

}  // namespace

std::string writeReport(const Manifest& manifest, const std::string& resultsDir) {
    std::vector<Row> rows;
    for (const BatchJob& job : manifest.jobs)
        rows.push_back(
            Row{&job, &manifest.material(job.material), readJobResult(resultsDir, job.id)});
    markPareto(rows);
    const std::vector<ClassChoice> classes = recommendPerClass(manifest, rows);

    nlohmann::json data;
    data["title"] = "osgBTF leaderboard";
    data["generated"] = utcNow();
    data["holdout_fraction"] = manifest.holdoutFraction;
    data["metric_note"] =
        "Average error: per texel, the mean over the measured (view, light) pairs of the length of "
        "the RGB difference (Meseth et al. 2003, section 4.1), averaged over the texels scored; "
        "RMSE over every channel value, PSNR with peak 1. Held-out: the same on the pairs left "
        "out of a second fit (a fraction " +
        cell(manifest.holdoutFraction, 3) +
        " of them, whole directions), evaluated between the directions that fit kept, and the "
        "SSIM (Wang et al. 2004) of up to 8 whole held-out images. Bytes "
        "per texel as stored for rendering; compression against 8-bit RGB per measured pair.";
    data["materials"] = nlohmann::json::array();
    for (const BatchMaterial& m : manifest.materials)
        data["materials"].push_back({{"name", m.name},
                                     {"class", m.materialClass},
                                     {"input", m.input},
                                     {"width", m.width},
                                     {"height", m.height},
                                     {"views", m.views},
                                     {"lights", m.lights}});
    data["rows"] = nlohmann::json::array();
    for (const Row& row : rows) {
        const JobResult& r = row.result;
        const bool done = row.done();
        const auto measured = [&](double value) { return done ? finiteOrNull(value) : nullptr; };
        data["rows"].push_back(
            {{"job", row.job->id},
             {"material", row.material->name},
             {"class", row.material->materialClass},
             {"method", row.job->method},
             {"options", optionsText(row.job->options)},
             {"status", r.state == JobState::Done     ? "done"
                        : r.state == JobState::Failed ? "failed"
                                                      : "pending"},
             {"failure", r.failure},
             {"avg", measured(r.average)},
             {"rmse", measured(r.rmse)},
             {"psnr", measured(r.psnr)},
             {"heldout_avg", measured(r.heldOutAverage)},
             {"heldout_rmse", measured(r.heldOutRmse)},
             {"heldout_psnr", measured(r.heldOutPsnr)},
             {"heldout_ssim", measured(r.heldOutSsim)},
             {"bytes_per_texel", measured(r.bytesPerTexel)},
             {"compression_ratio", measured(r.compressionRatio)},
             {"fit_seconds", measured(r.fitSeconds)},
             {"wall_seconds", measured(r.wallSeconds)},
             {"peak_rss_bytes", done ? nlohmann::json(r.peakRssBytes) : nlohmann::json(nullptr)},
             {"estimated_peak_bytes", row.job->estimatedPeakBytes},
             {"gpu_ms", nullptr},
             {"pareto", row.pareto}});
    }
    data["classes"] = nlohmann::json::array();
    for (const ClassChoice& c : classes)
        data["classes"].push_back({{"class", c.name},
                                   {"materials", c.materials},
                                   {"recommended", c.recommended},
                                   {"reason", c.reason}});

    // report.md
    std::size_t done = 0, failed = 0;
    double jobSeconds = 0;
    for (const Row& row : rows) {
        done += row.done();
        failed += row.result.state == JobState::Failed;
        if (row.done()) jobSeconds += row.result.wallSeconds;
    }
    std::ostringstream md;
    md << "# osgBTF leaderboard\n\n"
       << manifest.materials.size() << " materials, " << rows.size() << " jobs: " << done
       << " done, " << failed << " failed, " << rows.size() - done - failed
       << " pending. Generated " << data["generated"].get<std::string>()
       << " by `btf batch report`; index.html has the same with sortable tables and plots.\n\n"
       << data["metric_note"].get<std::string>() << "\n\n## Recommended method per class\n\n"
       << "| class | materials | recommended | why |\n|---|---|---|---|\n";
    for (const ClassChoice& c : classes)
        md << "| " << c.name << " | " << c.materials << " | "
           << (c.recommended.empty() ? "–" : c.recommended) << " | " << c.reason << " |\n";
    md << "\n## Every job\n\n| material | class | method | options | avg error | RMSE | PSNR dB | "
          "held-out avg | held-out PSNR dB | held-out SSIM | bytes/texel | ratio | fit s | job s | "
          "peak memory | "
          "estimated | Pareto "
          "|\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& row : rows) {
        const JobResult& r = row.result;
        md << "| " << row.material->name << " | " << row.material->materialClass << " | "
           << row.job->method << " | " << optionsText(row.job->options) << " | ";
        if (!row.done()) {
            md << (r.state == JobState::Failed ? "failed: " + r.failure : std::string("pending"))
               << " | | | | | | | | | | | | " << formatBytes(row.job->estimatedPeakBytes)
               << " | |\n";
            continue;
        }
        md << cell(r.average, 5) << " | " << cell(r.rmse, 5) << " | " << cell(r.psnr, 4) << " | "
           << cell(r.heldOutAverage, 5) << " | " << cell(r.heldOutPsnr, 4) << " | "
           << cell(r.heldOutSsim, 4) << " | " << cell(r.bytesPerTexel, 5) << " | "
           << cell(r.compressionRatio, 4) << ":1 | " << cell(r.fitSeconds, 3) << " | "
           << cell(r.wallSeconds, 3) << " | " << formatBytes(r.peakRssBytes) << " | "
           << formatBytes(row.job->estimatedPeakBytes) << " | " << (row.pareto ? "yes" : "")
           << " |\n";
    }
    if (done)
        md << "\nJob time: " << cell(jobSeconds, 4) << " s in all, "
           << cell(jobSeconds / double(done), 4) << " s per completed job (fit, scoring, held-out "
           << "fit and saving, one process each).\n";

    // results.csv
    std::ostringstream csv;
    csv << "job,material,class,method,options,status,failure,avg,rmse,psnr,heldout_avg,"
           "heldout_rmse,heldout_psnr,heldout_ssim,heldout_pairs,error_texels,bytes_per_texel,"
           "compression_ratio,fit_seconds,heldout_fit_seconds,wall_seconds,peak_rss_bytes,"
           "estimated_peak_bytes,pareto\n";
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const Row& row = rows[i];
        const JobResult& r = row.result;
        const nlohmann::json& json = data["rows"][i];
        const bool d = row.done();
        csv << csvText(row.job->id) << "," << csvText(row.material->name) << ","
            << csvText(row.material->materialClass) << "," << csvText(row.job->method) << ","
            << csvText(optionsText(row.job->options)) << "," << json["status"].get<std::string>()
            << "," << csvText(r.failure) << "," << (d ? csvNumber(r.average) : "") << ","
            << (d ? csvNumber(r.rmse) : "") << "," << (d ? csvNumber(r.psnr) : "") << ","
            << (d ? csvNumber(r.heldOutAverage) : "") << "," << (d ? csvNumber(r.heldOutRmse) : "")
            << "," << (d ? csvNumber(r.heldOutPsnr) : "") << ","
            << (d ? csvNumber(r.heldOutSsim) : "") << ","
            << (d ? std::to_string(r.heldOutPairs) : "") << ","
            << (d ? std::to_string(r.errorTexels) : "") << ","
            << (d ? csvNumber(r.bytesPerTexel) : "") << ","
            << (d ? csvNumber(r.compressionRatio) : "") << "," << (d ? csvNumber(r.fitSeconds) : "")
            << "," << (d ? csvNumber(r.heldOutFitSeconds) : "") << ","
            << (d ? csvNumber(r.wallSeconds) : "") << ","
            << (d ? std::to_string(r.peakRssBytes) : "") << "," << row.job->estimatedPeakBytes
            << "," << (row.pareto ? 1 : 0) << "\n";
    }

    // index.html: the JSON in a script, every '<' as \u003c (the same string in JSON): no value
    // can close the script or open a comment ("<!--<script>" would swallow the rest of the page).
    std::string json;
    for (const char c : data.dump()) json += c == '<' ? std::string("\\u003c") : std::string(1, c);
    std::string page = leaderboardPageTemplate;
    const std::string placeholder = "/*OSGBTF_LEADERBOARD_DATA*/null";
    const auto at = page.find(placeholder);
    if (at == std::string::npos)
        throw Error("harness/batch/leaderboard.html: the page has no " + placeholder);
    page.replace(at, placeholder.size(), json);

    const fs::path folder(resultsDir);
    writeTextAtomically((folder / "report.md").string(), md.str());
    writeTextAtomically((folder / "results.csv").string(), csv.str());
    const std::string pretty = data.dump(2) + "\n";
    writeTextAtomically((folder / "results.json").string(), pretty);
    writeTextAtomically((folder / "index.html").string(), page);
    return pretty;
}

}  // namespace osgBTF::batch

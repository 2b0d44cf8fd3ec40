// `btf batch plan`: which measured BTFs a folder holds, one job per material and method, and
// the manifest that every later step reads.
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <set>

#include <nlohmann/json.hpp>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/Progress.h"
#include "harness/batch/Batch.h"
#include "harness/batch/BatchFiles.h"
#include "loaders/LoadBtf.h"
#include "loaders/Rti.h"
#include "loaders/Ubo2003.h"
#include "materials/MethodOptions.h"
#include "materials/MethodRegistry.h"

namespace osgBTF::batch {

namespace fs = std::filesystem;

namespace {

std::string lower(std::string text) {
    for (char& c : text) c = char(std::tolower(static_cast<unsigned char>(c)));
    return text;
}

bool holdsUbo2003Images(const fs::path& folder) {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
        Ubo2003Name name;
        if (entry.is_regular_file(ec) && parseUbo2003Name(entry.path().filename().string(), name))
            return true;
    }
    return false;
}

/** An RTI capture set: a light-position file (".lp", any case) among the folder's own files. */
bool holdsLightPositionFile(const fs::path& folder) {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(folder, ec))
        if (entry.is_regular_file(ec) && lower(entry.path().extension().string()) == ".lp")
            return true;
    return false;
}

/** A folder that is one measured BTF (UBO2003-named images, or an RTI set), not searched further.
 */
bool isCaptureFolder(const fs::path& folder) {
    return holdsUbo2003Images(folder) || holdsLightPositionFile(folder);
}

/** Letters, digits, '.', '_' and '-' (a job id is a folder name and a Slurm argument). */
std::string safeName(const std::string& text) {
    std::string out;
    for (const char c : text)
        out += std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-'
                   ? c
                   : '_';
    return out.empty() ? "_" : out;
}

/** "carpet01" -> "carpet", "wool-2" -> "wool"; the name itself when nothing else is left. */
std::string classFromName(const std::string& name) {
    std::string stem = name;
    while (!stem.empty() && (std::isdigit(static_cast<unsigned char>(stem.back())) ||
                             stem.back() == '-' || stem.back() == '_' || stem.back() == ' '))
        stem.pop_back();
    return stem.empty() ? name : stem;
}

/** The inputs as (path, the folder it was found in or empty). */
std::vector<std::pair<std::string, std::string>> expandInputs(const std::vector<std::string>& in) {
    std::vector<std::pair<std::string, std::string>> found;
    for (const std::string& input : in) {
        std::error_code ec;
        if (!fs::exists(input, ec)) fail(input, "no such file or folder");
        if (fs::is_directory(input) && !isCaptureFolder(input)) {
            const std::vector<std::string> btfs = findMeasuredBtfs(input);
            if (btfs.empty())
                fail(input,
                     "no measured BTF found (UBO2014 .btf files, UBO2003/ATRIUM zips, folders "
                     "of UBO2003-named images, RTI sets: images with their .lp file)");
            for (const std::string& path : btfs) found.emplace_back(path, input);
        } else if (fs::is_regular_file(input) &&
                   lower(fs::path(input).extension().string()) == ".txt") {
            // A list: one path per line, relative to the list's folder.
            std::ifstream list(input);
            std::string line;
            while (std::getline(list, line)) {
                line.erase(0, line.find_first_not_of(" \t"));
                line.erase(line.find_last_not_of(" \t\r") + 1);
                if (line.empty() || line[0] == '#') continue;
                fs::path path(line);
                if (path.is_relative()) path = fs::path(input).parent_path() / path;
                found.emplace_back(path.string(), "");
            }
        } else {
            found.emplace_back(input, "");
        }
    }
    return found;
}

}  // namespace

std::string utcNow() {
    const std::time_t now = std::time(nullptr);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
    return text;
}

LoadOptions manifestLoadOptions(const std::string& storage, const std::string& decode) {
    LoadOptions load;
    load.storage = storage == "half" ? Storage::Half : Storage::Float;
    load.curve = decodeCurveFromName(decode);
    return load;
}

std::vector<std::string> findMeasuredBtfs(const std::string& folder) {
    std::vector<std::string> found;
    std::error_code ec;
    fs::recursive_directory_iterator it(folder, fs::directory_options::skip_permission_denied, ec),
        end;
    if (ec) fail(folder, "cannot read: " + ec.message());
    for (; it != end; it.increment(ec)) {
        if (ec) break;
        const fs::path& path = it->path();
        const std::string extension = lower(path.extension().string());
        if (it->is_directory(ec)) {
            if (isCaptureFolder(path)) {
                found.push_back(path.string());
                it.disable_recursion_pending();
            }
        } else if (it->is_regular_file(ec)) {
            if (extension == ".btf" || (extension == ".zip" && (mayBeUbo2003(path.string()) ||
                                                                isRtiCapture(path.string()))))
                found.push_back(path.string());
        }
    }
    std::sort(found.begin(), found.end());
    return found;
}

std::uint64_t estimatePeakBytes(const BatchMaterial& material, const std::string& method) {
    // The program (150-200 MiB: its libraries, a UBO2014 file's decoded blocks), the input as
    // opened, and the method's own measured working set (MethodInfo::fitWorkingSet; docs/batch.md
    // has the figures).
    const MethodInfo& info = findMethod(method);
    const std::uint64_t mib = std::uint64_t(1) << 20;
    const std::uint64_t values = std::uint64_t(material.width) * std::uint64_t(material.height) *
                                 material.views * material.lights * 3 * sizeof(float);
    std::uint64_t working = std::uint64_t(double(values) * info.fitWorkingSet);
    // A UBO2014 file is decoded block by block: at most what a 400 x 400 fit measured (lpca's
    // training set does not shrink with the file: 1.73 GB for a 64 x 64 one).
    if (material.factored)
        working =
            std::min(working, std::uint64_t(info.fitWorkingSetFullSizeGiB * 1024 * double(mib)));
    return 192 * mib + material.inputBytes + working +
           std::uint64_t(info.fitTablesMiB * double(mib));
}

const BatchMaterial& Manifest::material(const std::string& name) const {
    for (const BatchMaterial& m : materials)
        if (m.name == name) return m;
    throw Error("manifest: no material '" + name + "'");
}

const BatchJob& Manifest::job(const std::string& id) const {
    for (const BatchJob& j : jobs)
        if (j.id == id) return j;
    throw Error("no job '" + id + "' in the manifest");
}

Manifest planBatch(const PlanOptions& options) {
    if (options.methods.empty()) throw Error("--methods: no method named");
    if (!(options.holdoutFraction >= 0 && options.holdoutFraction <= 0.5))
        throw Error("--holdout-fraction: must be in [0, 0.5]");
    for (const std::string& method : options.methods) {
        const MethodInfo& info = findMethod(method);
        const auto given = options.methodOptions.find(method);
        if (given != options.methodOptions.end()) validateOptions(info, FitOptions(given->second));
    }
    for (const auto& [method, values] : options.methodOptions)
        if (std::find(options.methods.begin(), options.methods.end(), method) ==
            options.methods.end())
            throw Error("--set " + method + ":...: method '" + method + "' is not planned");

    Manifest manifest;
    manifest.created = utcNow();
    manifest.holdoutFraction = options.holdoutFraction;
    manifest.errorTexels = options.errorTexels;
    manifest.storage = options.storage;
    manifest.decode = options.decode;
    const LoadOptions load = manifestLoadOptions(options.storage, options.decode);

    const auto inputs = expandInputs(options.inputs);
    std::set<std::string> names, paths;
    Progress progress("reading the materials' headers", inputs.size());
    for (const auto& [input, root] : inputs) {
        const std::string path = fs::absolute(input).lexically_normal().string();
        if (!paths.insert(path).second) {
            progress.advance();
            continue;
        }
        BatchMaterial material;
        material.input = path;
        const fs::path asPath(path);
        const bool folder = fs::is_directory(asPath);
        // An RTI set named by its .lp file ("dirs.lp", as capture tools call it) is its folder.
        const bool lightPositions = !folder && lower(asPath.extension().string()) == ".lp";
        const std::string stem = folder           ? asPath.filename().string()
                                 : lightPositions ? asPath.parent_path().filename().string()
                                                  : asPath.stem().string();
        material.name = safeName(stem);
        for (int n = 2; names.count(material.name); ++n)
            material.name = safeName(stem) + "-" + std::to_string(n);
        names.insert(material.name);
        const fs::path parent = asPath.parent_path();
        const bool inSubfolder = !root.empty() && fs::absolute(root).lexically_normal() != parent &&
                                 fs::absolute(root).lexically_normal() / "" != parent / "";
        material.materialClass = inSubfolder ? parent.filename().string() : classFromName(stem);
        const std::unique_ptr<BtfSource> source = openBtfSource(path, load);
        material.width = source->width();
        material.height = source->height();
        material.views = source->viewCount();
        material.lights = source->lightCount();
        material.factored = !source->inMemory();
        material.inputBytes = source->inMemory()
                                  ? source->decodedBytes() / (load.storage == Storage::Half ? 2 : 1)
                                  : std::uint64_t(fs::file_size(asPath));
        manifest.materials.push_back(material);
        for (const std::string& method : options.methods) {
            BatchJob job;
            job.material = material.name;
            job.method = method;
            const auto given = options.methodOptions.find(method);
            if (given != options.methodOptions.end()) job.options = given->second;
            job.id = material.name + "--" + method;
            for (const auto& [key, value] : job.options) job.id += "--" + key + "=" + value;
            job.id = safeName(job.id);
            job.estimatedPeakBytes = estimatePeakBytes(material, method);
            manifest.jobs.push_back(job);
        }
        progress.advance();
    }
    if (manifest.materials.empty()) throw Error("no measured BTF to plan");
    return manifest;
}

void writeManifest(const Manifest& manifest, const std::string& resultsDir) {
    std::error_code ec;
    fs::create_directories(fs::path(resultsDir) / "jobs", ec);
    if (ec) fail(resultsDir, "cannot create: " + ec.message());
    nlohmann::json json;
    json["version"] = manifest.version;
    json["created"] = manifest.created;
    json["holdout_fraction"] = manifest.holdoutFraction;
    json["error_texels"] = manifest.errorTexels;
    json["storage"] = manifest.storage;
    json["decode"] = manifest.decode;
    json["materials"] = nlohmann::json::array();
    for (const BatchMaterial& m : manifest.materials)
        json["materials"].push_back({{"name", m.name},
                                     {"class", m.materialClass},
                                     {"input", m.input},
                                     {"width", m.width},
                                     {"height", m.height},
                                     {"views", m.views},
                                     {"lights", m.lights},
                                     {"factored", m.factored},
                                     {"input_bytes", m.inputBytes}});
    json["jobs"] = nlohmann::json::array();
    for (const BatchJob& j : manifest.jobs)
        json["jobs"].push_back({{"id", j.id},
                                {"material", j.material},
                                {"method", j.method},
                                {"options", j.options},
                                {"estimated_peak_bytes", j.estimatedPeakBytes}});
    writeTextAtomically((fs::path(resultsDir) / "manifest.json").string(), json.dump(2) + "\n");
}

Manifest readManifest(const std::string& resultsDir) {
    const std::string path = (fs::path(resultsDir) / "manifest.json").string();
    std::ifstream in(path);
    if (!in) fail(resultsDir, "no manifest.json (run `btf batch plan` first)");
    Manifest manifest;
    try {
        const nlohmann::json json = nlohmann::json::parse(in);
        manifest.version = json.at("version").get<int>();
        if (manifest.version != 1)
            fail(path, "version " + std::to_string(manifest.version) + " is not 1");
        manifest.created = json.value("created", "");
        manifest.holdoutFraction = json.at("holdout_fraction").get<double>();
        manifest.errorTexels = json.at("error_texels").get<long long>();
        manifest.storage = json.value("storage", "float");
        manifest.decode = json.value("decode", "linear");
        for (const auto& m : json.at("materials")) {
            BatchMaterial material;
            material.name = m.at("name").get<std::string>();
            material.materialClass = m.at("class").get<std::string>();
            material.input = m.at("input").get<std::string>();
            material.width = m.at("width").get<int>();
            material.height = m.at("height").get<int>();
            material.views = m.at("views").get<std::size_t>();
            material.lights = m.at("lights").get<std::size_t>();
            material.factored = m.at("factored").get<bool>();
            material.inputBytes = m.at("input_bytes").get<std::uint64_t>();
            manifest.materials.push_back(material);
        }
        for (const auto& j : json.at("jobs")) {
            BatchJob job;
            job.id = j.at("id").get<std::string>();
            job.material = j.at("material").get<std::string>();
            job.method = j.at("method").get<std::string>();
            job.options = j.at("options").get<std::map<std::string, std::string>>();
            job.estimatedPeakBytes = j.at("estimated_peak_bytes").get<std::uint64_t>();
            manifest.jobs.push_back(job);
        }
    } catch (const nlohmann::json::exception& e) {
        fail(path, std::string("not a batch manifest: ") + e.what());
    }
    return manifest;
}

std::string jobFolder(const std::string& resultsDir, const std::string& id) {
    return (fs::path(resultsDir) / "jobs" / id).string();
}

const char* jobStateName(JobState state) {
    switch (state) {
        case JobState::Pending:
            return "pending";
        case JobState::Running:
            return "running";
        case JobState::Done:
            return "done";
        case JobState::Failed:
            return "failed";
    }
    return "?";
}

JobResult readJobResult(const std::string& resultsDir, const std::string& id) {
    JobResult result;
    result.id = id;
    const fs::path folder = jobFolder(resultsDir, id);
    if (jobLockHeld((folder / "lock").string())) {
        result.state = JobState::Running;
        return result;
    }
    std::ifstream in(folder / "result.json");
    if (!in) return result;
    try {
        result = jobResultFromJson(nlohmann::json::parse(in));
    } catch (const std::exception& e) {
        // Written atomically, so only a hand-edited file gets here: run the job again.
        result = JobResult{};
        result.id = id;
    }
    return result;
}

}  // namespace osgBTF::batch

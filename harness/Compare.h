// osgBTF harness: compare compression methods on one measured BTF (`btf compare`).
//
// runCompare() fits every method in a child process (reusing earlier fits), computes the error
// tables on the CPU, spot-checks the GPU path, times one rendering pass per method against the
// empty pass and a calibration pass in each target, draws the pictures and writes report.md,
// results.csv and results.json into the output folder. Table definitions: harness/README.md.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/ErrorMetrics.h"
#include "harness/FitRunner.h"
#include "harness/HeldOut.h"
#include "harness/MaterialShaderCost.h"
#include "harness/PassCost.h"
#include "loaders/LoadOptions.h"
#include "materials/Material.h"

namespace osgBTF {

/** The methods "all" stands for: every registered method with MethodInfo::compareAll, by
 *  MethodInfo::order (lambert, the baseline, is always added). */
std::vector<std::string> allCompareMethods();

struct CompareOptions {
    std::string input;
    std::string outputDir;
    /** Methods to compare; the baseline "lambert" is added first if missing. */
    std::vector<std::string> methods = allCompareMethods();
    /** Per method options (KEY -> VALUE), handed to `btf fit --set`. */
    std::map<std::string, std::map<std::string, std::string>> methodOptions;
    std::string fitTool;  ///< the btf executable; defaultFitTool() when empty
    std::vector<std::string> fitGlobalArguments;  ///< before `fit` (e.g. --memory-limit 8G)
    std::vector<std::string> fitExtraArguments;   ///< after `fit` (e.g. --storage half)
    LoadOptions load;  ///< how the harness itself loads INPUT (must match fitExtraArguments)
    bool reuseFits = true;
    bool gpu = true;  ///< GPU spot check, pass timing and renders (headless OpenGL)
    PassSettings pass;
    int sphereSize = 192;
    float sphereTextureScale = 4;
    /** An HDR lat-long environment (scene/EnvironmentLight.h): adds pictures/environment.png, the
     *  sample patch lit by it with every method (GPU). Empty: none. */
    std::string envFile;
    float envExposure = 1, envRotation = 0;
    double maxBytesPerTexel = 0;  ///< 0: no budget
    double maxMsPerPass = 0;      ///< 0: no budget
    /** Texels the error tables compare (a random subsample, all pairs each); 0 = all; -1 = all
     *  for data in memory, 4096 for a UBO2014 file (decoded per block, never whole). */
    long long errorTexels = -1;
    /** Each method is fitted a second time without this fraction of the (view, light) pairs
     *  (whole directions: harness/batch/Holdout.h) and scored on them: error, PSNR and SSIM
     *  (harness/HeldOut.h), the RTI field's figures. 0: no held-out fits. */
    double holdoutFraction = 0.1;
    /** Already fitted files (an osgBTF fitted material, a .ptm, an .rti, a relight
     *  DIR/info.json: anything loadMaterial reads), each a row beside the fitted methods,
     *  evaluated at the BTF's measured directions (Material::evaluate; for an RTI capture its
     *  lights) and labelled with its file name (MethodResult::label). Not fitted, not held out,
     *  never the recommendation. */
    std::vector<std::string> materialFiles;
};

struct MethodResult {
    std::string method;  ///< for a given file: its material's method (empty until it loads)
    /** A file given with CompareOptions::materialFiles, as given; empty for a fitted method. */
    std::string file;
    /** The row's name in the tables, pictures, CSV and JSON: the method, or for a given file
     *  "file:NAME" (NAME its file name; for relight's info.json the folder's too). */
    std::string label() const;
    std::map<std::string, std::string> options;
    bool failed = false;
    std::string failure;     ///< "failed: ..." text shown in every table
    std::string fittedFile;  ///< relative to the output folder, e.g. "fits/pca.exr"
    FitProcessResult fit;    ///< child process: wall time, peak memory, reused
    double fitSeconds = -1;  ///< fitInfo["seconds"] from the file (the fit alone)
    ErrorSummary error;
    MemoryFootprint memory;
    double compressionRatio = 0;  ///< raw bytes per texel / bytes per texel
    ShaderCost cost;
    double gpuCpuMaxDifference = -1;  ///< -1: not checked
    /** The held-out fit (CompareOptions::holdoutFraction) and its scores; heldOutFile empty: none
     *  was made; heldOutFailure set: it or its scoring failed (the method's row stands). */
    std::string heldOutFile;
    FitProcessResult heldOutFit;
    double heldOutFitSeconds = -1;
    std::string heldOutFailure;
    HeldOutScores heldOut;
    bool heldOutScored() const { return !heldOutFile.empty() && heldOutFailure.empty(); }
    /** One per pass target (CompareResult::calibrations' order); empty: not measured. */
    std::vector<MethodPass> passes;
    /** The pass in the first target (what the time budget reads), null when not measured. */
    const MethodPass* primaryPass() const {
        return passes.empty() || !passes.front().measured() ? nullptr : &passes.front();
    }
};

struct ComparePicture {
    std::string file;  ///< relative to the output folder
    std::string caption;
};

struct CompareResult {
    std::string input;
    int width = 0, height = 0;
    std::size_t views = 0, lights = 0;
    double rawBytesPerTexel = 0;  ///< views x lights x 3 bytes (8-bit RGB, as the Bonn data)
    std::uint64_t rawTotalBytes = 0;
    /** Texels the errors are computed on: width x height, or a random subsample's size. */
    std::size_t errorTexels = 0;
    double holdoutFraction = 0;
    std::string holdoutNote;            ///< the split (or why there is none)
    std::vector<MethodResult> methods;  ///< the baseline first
    // GPU part
    bool gpuRan = false;
    std::string gpuNote;  ///< why the GPU part is missing, or the renderer
    std::string glRenderer, glVersion;
    bool softwareRenderer = false;
    PassSettings pass;
    std::vector<Calibration> calibrations;  ///< one per pass target, in PassSettings order
    std::vector<std::pair<std::size_t, std::size_t>> spotCheckPairs;  ///< (view, light) indices
    bool labelsDrawn = false;  ///< text labels in the pictures (a font was found)
    double errorMapMax = 0;    ///< the colour scale of the error maps: 0 .. this
    std::vector<ComparePicture> pictures;
    // Recommendation
    double maxBytesPerTexel = 0, maxMsPerPass = 0;
    std::string recommended;     ///< method name, empty if none fits
    std::string recommendation;  ///< the line for the report
};

/** Lowest average error among the completed methods within the budgets (0 = no budget; a time
 *  budget needs a measured pass time). Fills recommended and recommendation. */
void recommend(CompareResult& result);

/** Does everything; writes into a temporary folder beside outputDir and renames it to outputDir
 *  at the end (an existing outputDir is replaced). Throws Error (and leaves no outputDir behind
 *  when there was none) for an unreadable INPUT, an unknown method, or an unwritable folder; a
 *  method that fails is reported in the result and the tables instead. Progress bars per stage. */
CompareResult runCompare(const CompareOptions& options);

}  // namespace osgBTF

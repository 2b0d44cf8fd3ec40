// A `btf batch` results folder written by hand from harness/batch/README.md's description of
// manifest.json and jobs/<id>/result.json, not by the code that runs jobs: three materials in two
// classes, three methods, one failed job and one never run. The numbers are chosen so that the
// Pareto front and the recommendations follow by hand:
//   wool01 (fabric):  lambert 6 B 0.06 | pca 40 B 0.01 | ptm 36 B 0.07 (dominated by lambert)
//   wool02 (fabric):  lambert 6 B 0.07 | pca failed    | ptm 36 B 0.02
//   stone01 (stone):  lambert 6 B 0.04 | pca 40 B 0.005 | ptm pending
// Held-out means per class over the methods done on all its materials: fabric lambert
// (0.058 + 0.068) / 2 = 0.063, ptm (0.072 + 0.05) / 2 = 0.061 -> ptm (pca failed on wool02);
// stone lambert 0.041, pca 0.02 -> pca.
#pragma once

#include <filesystem>
#include <string>

#include "tests/TestUtil.h"

namespace osgBTF::test {

inline void writeHandMadeBatch(const std::filesystem::path& results) {
    namespace fs = std::filesystem;
    const char* manifest = R"({
  "version": 1, "created": "2026-12-02T00:00:00Z", "holdout_fraction": 0.1, "error_texels": -1,
  "storage": "float", "decode": "linear",
  "materials": [
    {"name": "wool01", "class": "fabric", "input": "/data/fabric/wool01.zip", "width": 8,
     "height": 8, "views": 81, "lights": 81, "factored": false, "input_bytes": 5038848},
    {"name": "wool02", "class": "fabric", "input": "/data/fabric/wool02.zip", "width": 8,
     "height": 8, "views": 81, "lights": 81, "factored": false, "input_bytes": 5038848},
    {"name": "stone01", "class": "stone", "input": "/data/stone01.zip", "width": 8,
     "height": 8, "views": 81, "lights": 81, "factored": false, "input_bytes": 5038848}
  ],
  "jobs": [
    {"id": "wool01--lambert", "material": "wool01", "method": "lambert", "options": {}, "estimated_peak_bytes": 200000000},
    {"id": "wool01--pca", "material": "wool01", "method": "pca", "options": {}, "estimated_peak_bytes": 200000000},
    {"id": "wool01--ptm", "material": "wool01", "method": "ptm", "options": {}, "estimated_peak_bytes": 200000000},
    {"id": "wool02--lambert", "material": "wool02", "method": "lambert", "options": {}, "estimated_peak_bytes": 200000000},
    {"id": "wool02--pca", "material": "wool02", "method": "pca", "options": {}, "estimated_peak_bytes": 200000000},
    {"id": "wool02--ptm", "material": "wool02", "method": "ptm", "options": {}, "estimated_peak_bytes": 200000000},
    {"id": "stone01--lambert", "material": "stone01", "method": "lambert", "options": {}, "estimated_peak_bytes": 200000000},
    {"id": "stone01--pca", "material": "stone01", "method": "pca", "options": {}, "estimated_peak_bytes": 200000000},
    {"id": "stone01--ptm", "material": "stone01", "method": "ptm", "options": {}, "estimated_peak_bytes": 200000000}
  ]
})";
    fs::create_directories(results / "jobs");
    writeTextFile((results / "manifest.json").string(), manifest);
    const auto done = [&](const std::string& id, double avg, double heldOut, double bytes) {
        fs::create_directories(results / "jobs" / id);
        writeTextFile((results / "jobs" / id / "result.json").string(),
                      "{\"id\": \"" + id + "\", \"state\": \"done\", \"failure\": \"\", \"avg\": " +
                          std::to_string(avg) + ", \"rmse\": " + std::to_string(avg) +
                          ", \"psnr\": 30, \"heldout_avg\": " + std::to_string(heldOut) +
                          ", \"heldout_rmse\": " + std::to_string(heldOut) +
                          ", \"heldout_psnr\": 28, \"heldout_pairs\": 632, \"error_texels\": "
                          "64, \"bytes_per_texel\": " +
                          std::to_string(bytes) +
                          ", \"compression_ratio\": " + std::to_string(19683.0 / bytes) +
                          ", \"fit_seconds\": 1.5, \"heldout_fit_seconds\": 1.25, "
                          "\"wall_seconds\": 3, \"peak_rss_bytes\": 123456789, \"host\": "
                          "\"hand\"}\n");
    };
    done("wool01--lambert", 0.06, 0.058, 6);
    done("wool01--pca", 0.01, 0.03, 40);
    done("wool01--ptm", 0.07, 0.072, 36);
    done("wool02--lambert", 0.07, 0.068, 6);
    done("wool02--ptm", 0.02, 0.05, 36);
    done("stone01--lambert", 0.04, 0.041, 6);
    done("stone01--pca", 0.005, 0.02, 40);
    fs::create_directories(results / "jobs" / "wool02--pca");
    writeTextFile((results / "jobs" / "wool02--pca" / "result.json").string(),
                  R"({"id": "wool02--pca", "state": "failed",
                      "failure": "/data/fabric/wool02.zip: no such file <!--<script>",
                      "peak_rss_bytes": 1000})");
}

}  // namespace osgBTF::test

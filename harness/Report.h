// osgBTF harness: the comparison written as report.md, results.csv and results.json.
#pragma once

#include <string>

#include "harness/Compare.h"

namespace osgBTF {

std::string reportMarkdown(const CompareResult& result);
/** One row per method; numbers with full precision (%.17g); empty cells where not measured. */
std::string resultsCsv(const CompareResult& result);
std::string resultsJson(const CompareResult& result);

}  // namespace osgBTF

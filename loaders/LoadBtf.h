// osgBTF: one entry point for every measured-BTF file osgBTF reads.
#pragma once

#include <memory>
#include <string>

#include "core/BtfSource.h"
#include "core/MeasuredBtf.h"
#include "loaders/LoadOptions.h"

namespace osgBTF {

/** Loads a UBO2003/ATRIUM zip (".zip"), a UBO2014 file (".btf"), a folder of UBO2003-named
 *  images, or an RTI set (a ".lp" light-position file, or a folder or zip holding one and no
 *  UBO2003-named image: loadRti); files with another extension are recognised by their first
 *  bytes. Sets
 *  MeasuredBtf::source to path. Throws osgBTF::Error("<path>: <problem>"), e.g. "no such file",
 *  "file is empty", "cannot open: Permission denied". */
MeasuredBtf loadMeasuredBtf(const std::string& path, const LoadOptions& options = {});

/** Opens measured data for fitting and comparing: a UBO2014 file stays factored (a
 *  FactoredBtfSource that decodes the blocks a method reads; the factors are ~1/200 of the
 *  values of a full-size file), an RTI set goes through openRtiCapture (out of core when it is
 *  large: options.placement), anything else is loaded with loadMeasuredBtf. Same errors. */
std::unique_ptr<BtfSource> openBtfSource(const std::string& path, const LoadOptions& options = {});

/** Whether loadMeasuredBtf would read `path` as a UBO2014 file: a file (not a folder) named
 *  ".btf" (any case), or not named ".zip" and starting with '!'. False for what cannot be opened;
 *  says nothing about whether the file is valid. */
bool isUbo2014File(const std::string& path);

}  // namespace osgBTF

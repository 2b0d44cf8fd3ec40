// osgbtf: the Python module, a thin pybind11 layer over the C++ API (python/README.md,
// docs/python.md). This file is its table of contents; each concern has its binding file:
//   MeasuredBindings.cpp  measured BTFs: Btf, load, memory_limit, sample
//   MaterialBindings.cpp  fitted materials: methods, Material, open_material (CPU and GPU images)
//   FitBindings.cpp       fitting and scoring: fit, error, error_of, compare
// (python/Bindings.h: what they share).
#include <exception>

#include "core/Error.h"
#include "core/Progress.h"
#include "python/Bindings.h"

namespace py = pybind11;
using namespace osgBTF;

PYBIND11_MODULE(osgbtf, m) {
    m.doc() =
        "osgBTF from Python: measured BTFs, the compression methods, fitted materials, "
        "comparisons (docs/python.md).";
    static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const Progress::Cancelled& e) {
            PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
        } catch (const Error& e) {
            PyErr_SetString(error.ptr(), e.what());
        }
    });

    python::bindMeasuredBtfs(m);
    python::bindMaterials(m);
    python::bindFitting(m);

    m.attr("__version__") = "0.1.0";
}

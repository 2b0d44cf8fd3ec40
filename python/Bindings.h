// osgbtf, the Python module (python/osgbtf.cpp): what its binding files share. Each binding file
// defines the Python names of one concern; the module calls them in this order.
#pragma once

// Every binding file sees the same type casters (pybind11 requires it): the STL's and
// std::function's too.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>

#include <osg/ref_ptr>

#include "core/BtfSource.h"
#include "core/Directions.h"
#include "core/Error.h"
#include "materials/Material.h"

namespace osgBTF::python {

namespace py = pybind11;

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

/** osgbtf.Btf: a measured BTF. */
struct PyBtf {
    std::shared_ptr<const BtfSource> source;
    std::string path;  ///< empty for the in-memory sample
};

/** osgbtf.Material: a fitted material. */
struct PyMaterial {
    osg::ref_ptr<Material> material;
    const Material& get() const {
        if (!material) throw Error("the material was released");
        return *material;
    }
};

/** (n, 3) unit vectors of a direction set. */
py::array_t<float> directionVectors(const DirectionSet& set);

/** Btf, load, memory_limit, sample (MeasuredBindings.cpp). */
void bindMeasuredBtfs(py::module_& m);
/** methods, Material, open_material (MaterialBindings.cpp). */
void bindMaterials(py::module_& m);
/** fit, error, error_of, compare (FitBindings.cpp). */
void bindFitting(py::module_& m);

}  // namespace osgBTF::python

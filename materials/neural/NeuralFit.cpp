// The neural method's fit (libosgBTFFit): options and shape here; the training itself (libtorch)
// is NeuralTraining.cpp's, a module loaded on the first neural fit (built when CMake found
// libtorch; without it the fit says what is missing).
#include "materials/MethodOptions.h"
#include "materials/neural/Neural.h"

#include <chrono>
#include <string>

#include "core/Error.h"
#include "core/Modules.h"

namespace osgBTF {

namespace {

using TrainFunction = void (*)(const BtfSource&, const OptionValues&, NeuralMaterial&);

/** osgbtfTrainNeural from libosgBTFNeuralTraining.so, next to this library (core/Modules.h),
 *  loaded once. */
TrainFunction trainer() {
    static const TrainFunction function = [] {
        std::string error;
        void* symbol = loadModuleSymbol(reinterpret_cast<const void*>(&trainer),
                                        "libosgBTFNeuralTraining.so", "osgbtfTrainNeural", error);
        if (!symbol)
            throw Error(
                "neural: fitting needs libtorch, and this osgBTF was built without it "
                "(install libtorch-dev and configure again); rendering a fitted neural "
                "material does not (" +
                error + ")");
        return reinterpret_cast<TrainFunction>(symbol);
    }();
    return function;
}

}  // namespace

osg::ref_ptr<NeuralMaterial> NeuralMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    const OptionValues o = validateOptions(kMethod, options);
    if (btf.empty()) throw Error("neural: the BTF is empty");
    const auto start = std::chrono::steady_clock::now();
    osg::ref_ptr<NeuralMaterial> m = new NeuralMaterial;
    m->setShape(btf.width(), btf.height(), btf.views(), btf.lights(), o.integer("latent"),
                o.integer("layers"), o.integer("units"));
    trainer()(btf, o, *m);
    m->fitInfo["seconds"] = std::to_string(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    m->fitInfo["steps"] = std::to_string(o.integer("steps"));
    return m;
}

namespace {
// The fit hook of the method registered in Neural.cpp (libosgBTF).
const bool neuralFitterRegistered = registerFitterClass<NeuralMaterial>();
}  // namespace

}  // namespace osgBTF

#include "materials/lambert/Lambert.h"

#include <tbb/parallel_for.h>

#include "core/Error.h"
#include "materials/MaterialState.h"

namespace osgBTF {

LambertMaterial::LambertMaterial(const LambertMaterial& other, const osg::CopyOp& copyop)
    : Material(other, copyop), albedo(other.albedo) {}

void LambertMaterial::assignFrom(const Material& other) {
    const LambertMaterial& o = assignCommon<LambertMaterial>(other);
    albedo = o.albedo;
}

osg::ref_ptr<LambertMaterial> LambertMaterial::fit(const BtfSource& btf,
                                                   const FitOptions& options) {
    validateOptions("lambert", options);  // it has none: anything given is an error
    osg::ref_ptr<LambertMaterial> m = new LambertMaterial;
    m->setGeometry(btf.width(), btf.height(), btf.views(), btf.lights());
    m->albedo.assign(btf.texelCount() * 3, 0.0f);
    double sumSquares = 0;
    for (std::size_t v = 0; v < btf.viewCount(); ++v)
        for (std::size_t l = 0; l < btf.lightCount(); ++l)
            sumSquares += double(btf.lights().vector(l).z) * btf.lights().vector(l).z;
    const std::size_t block = btf.abrdfBlockTexels(), texels = btf.texelCount(),
                      values = btf.imageCount() * 3;
    tbb::parallel_for(std::size_t(0), (texels + block - 1) / block, [&](std::size_t b) {
        const std::size_t first = b * block, count = std::min(block, texels - first);
        std::vector<float> abrdfs(count * values);
        btf.readAbrdfRange(first, count, abrdfs.data());
        for (std::size_t t = first; t < first + count; ++t) {
            const float* abrdf = abrdfs.data() + (t - first) * values;
            double sum[3] = {0, 0, 0};
            std::size_t i = 0;
            for (std::size_t v = 0; v < btf.viewCount(); ++v)
                for (std::size_t l = 0; l < btf.lightCount(); ++l, i += 3) {
                    const double lz = btf.lights().vector(l).z;
                    for (int c = 0; c < 3; ++c) sum[c] += abrdf[i + c] * lz;
                }
            // The model is what is stored: round to half now so CPU, file and GPU agree exactly.
            for (int c = 0; c < 3; ++c)
                m->albedo[t * 3 + c] = float(Imath::half(float(sum[c] / sumSquares)));
        }
    });
    return m;
}

glm::vec3 LambertMaterial::evaluate(int x, int y, const glm::vec3&, const glm::vec3& light) const {
    const std::size_t t = (std::size_t(y) * _width + x) * 3;
    return glm::vec3(albedo[t], albedo[t + 1], albedo[t + 2]) * light.z;
}

MemoryFootprint LambertMaterial::memory() const {
    return {3.0, 6.0, std::uint64_t(albedo.size()) * 2};
}

FittedMaterial LambertMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.textures.push_back({"albedo", _width, _height, 1, 3, MaterialTexture::Half, albedo});
    return file;
}

osg::ref_ptr<LambertMaterial> LambertMaterial::fromFile(const FittedMaterial& file) {
    osg::ref_ptr<LambertMaterial> m = new LambertMaterial;
    m->readCommon(file);
    const MaterialTexture& t = file.texture("albedo");
    if (t.width != m->_width || t.height != m->_height || t.channels != 3)
        fail(file.source, "texture 'albedo' must be " + std::to_string(m->_width) + "x" +
                              std::to_string(m->_height) + " RGB");
    m->albedo = t.data;
    return m;
}

osg::ref_ptr<osg::StateSet> LambertMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    addTexture(*stateSet,
               createFloatTexture({"albedo", _width, _height, 1, 3, MaterialTexture::Half, albedo},
                                  filtersBilinearly())
                   .get(),
               "lambertAlbedo", 0);
    return stateSet;
}

namespace {
const bool registered = registerMethod([] {
    MethodInfo m;
    m.name = "lambert";
    m.description = "plain lit texture: rho(x) * cos(theta_l), the baseline";
    m.fit = [](const BtfSource& btf, const FitOptions& o) -> osg::ref_ptr<Material> {
        return LambertMaterial::fit(btf, o);
    };
    m.load = [](const FittedMaterial& f) -> osg::ref_ptr<Material> {
        return LambertMaterial::fromFile(f);
    };
    m.createInstance = []() -> osg::Object* { return new LambertMaterial; };
    // One albedo fetch, times l_z.
    m.shaderCost = [](const Material&) { return ShaderCost::ofEvaluate(1, 1, "ALU 11, TEX 1"); };
    m.filtersLinearly = true;  // the value is the albedo times l_z
    m.baseline = true;
    m.compareAll = false;  // the comparison always adds it as its baseline
    m.order = 0;
    return m;
}());
}  // namespace

}  // namespace osgBTF

// The baseline's fit (libosgBTFFit): the least-squares albedo per texel.
#include "materials/MethodOptions.h"
#include "materials/lambert/Lambert.h"

#include <tbb/parallel_for.h>

#include "core/Error.h"

namespace osgBTF {

osg::ref_ptr<LambertMaterial> LambertMaterial::fit(const BtfSource& btf,
                                                   const FitOptions& options) {
    validateOptions(kMethod, options);  // it has none: anything given is an error
    osg::ref_ptr<LambertMaterial> m = new LambertMaterial;
    m->setGeometry(btf.width(), btf.height(), btf.views(), btf.lights());
    m->albedo = StoredValues(MaterialTexture::Half, btf.texelCount() * 3);
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
            for (int c = 0; c < 3; ++c) m->albedo.set(t * 3 + c, float(sum[c] / sumSquares));
        }
    });
    return m;
}

namespace {
// The fit hook of the method registered in Lambert.cpp (libosgBTF).
const bool lambertFitterRegistered = registerFitterClass<LambertMaterial>();
}  // namespace

}  // namespace osgBTF

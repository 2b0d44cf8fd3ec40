// Reads top to bottom: coefficients, the CPU field, the colour model in file and shader,
// registration (the fitter is PtmFit.cpp, in libosgBTFFit). Shape checks, view blending, memory,
// file, StateSet: materials/LightBasisMaterial.h. The model and its equation: Ptm.h.
#include "materials/ptm/Ptm.h"

#include "core/Error.h"
#include "core/FloatImage.h"
#include "materials/MaterialMath.h"
#include "materials/MethodRegistry.h"
#include "materials/RelightFolder.h"
#include "materials/RelightLayoutWriter.h"
#include "materials/ptm/PtmFile.h"

namespace osgBTF {

// ---- coefficients ------------------------------------------------------------------------------

std::array<double, PtmMaterial::kTerms> PtmMaterial::monomials(const glm::vec3& light) {
    const double x = light.x, y = light.y;
    return {x * x, y * y, x * y, x, y, 1.0};
}

float PtmMaterial::coefficient(std::size_t texel, int slot, int k, int c) const {
    const std::size_t texels = texelCount();
    if (_shape.luminance)
        return coefficients[((std::size_t(slot) * 2 + k / 3) * texels + texel) * 3 + k % 3];
    return coefficients[((std::size_t(slot) * kTerms + k) * texels + texel) * 3 + c];
}

void PtmMaterial::setCoefficient(std::size_t texel, int slot, int k, int c, float value) {
    const std::size_t texels = texelCount();
    if (_shape.luminance)
        coefficients.set(((std::size_t(slot) * 2 + k / 3) * texels + texel) * 3 + k % 3, value);
    else
        coefficients.set(((std::size_t(slot) * kTerms + k) * texels + texel) * 3 + c, value);
}

// ---- CPU evaluator -----------------------------------------------------------------------------

glm::vec3 PtmMaterial::field(std::size_t texel, int slot, float lx, float ly) const {
    // ptm.frag's ptmField, operation for operation.
    const float mx = lx * lx, my = ly * ly, mxy = lx * ly;
    const std::size_t texels = texelCount();
    if (_shape.luminance) {
        float a[3], b[3], rgb[3];
        coefficients.read(((std::size_t(slot) * 2) * texels + texel) * 3, 3, a);
        coefficients.read(((std::size_t(slot) * 2 + 1) * texels + texel) * 3, 3, b);
        float l = b[2];
        l += a[0] * mx;
        l += a[1] * my;
        l += a[2] * mxy;
        l += b[0] * lx;
        l += b[1] * ly;
        colour.read((std::size_t(slot) * texels + texel) * 3, 3, rgb);
        return glm::vec3(rgb[0], rgb[1], rgb[2]) * l;
    }
    const auto term = [&](int k) {
        const std::size_t p = ((std::size_t(slot) * kTerms + k) * texels + texel) * 3;
        return glm::vec3(coefficients[p], coefficients[p + 1], coefficients[p + 2]);
    };
    glm::vec3 sum = term(5);
    sum += term(0) * mx;
    sum += term(1) * my;
    sum += term(2) * mxy;
    sum += term(3) * lx;
    sum += term(4) * ly;
    return sum;
}

// ---- file and shader (the rest is LightBasisMaterial's) -----------------------------------------

void PtmMaterial::readShape(const FittedMaterial& file, Shape& shape) {
    const std::string colourModel = file.parameter("colour");
    if (colourModel != "rgb" && colourModel != "luminance")
        fail(file.source, "parameter 'colour' must be rgb or luminance, got '" + colourModel + "'");
    shape.luminance = colourModel == "luminance";
}

void PtmMaterial::writeShape(FittedMaterial& file) const {
    file.parameters["colour"] = _shape.luminance ? "luminance" : "rgb";
}

std::vector<std::string> PtmMaterial::shapeDefines() const {
    // The colour model is the program's, not a uniform: ptm.frag holds only the variant's code.
    if (_shape.luminance) return {"OSGBTF_PTM_LUMINANCE"};
    return {};
}

// ---- registration ------------------------------------------------------------------------------

namespace {
const bool ptmRegistered = registerMethodClass<PtmMaterial>([] {
    MethodInfo m;
    m.description =
        "polynomial texture maps (Malzbender 2001, as Boßerhoff and Nicoll 2003 use them): per "
        "texel a biquadratic in the "
        "light's (l_x, l_y), per channel or on the luminance times a base colour, fitted by one "
        "shared pseudo-inverse; on the front view or one per view, blended";
    m.options = {
        OptionSpec::choice("colour", "rgb", {"rgb", "luminance"},
                           "rgb: a polynomial per channel (18 coefficients per texel); luminance: "
                           "one on the Rec. 709 luminance times an RGB base colour of unit "
                           "luminance (6 + 3)"),
        OptionSpec::choice("views", "front", {"front", "all"},
                           "front: one PTM fitted on the measured view nearest the normal, used "
                           "for every view (the paper's); all: one PTM per measured view, blended "
                           "over the 3 Delaunay-neighbour views"),
        OptionSpec::choice("storage", "half", {"half", "float"},
                           "precision of the coefficients and the colour")};
    // A polynomial in the light whose coefficients are per texel (luminance materials excepted:
    // PtmMaterial::linearInParameters).
    m.filtersParameters = true;
    m.shaderCost = [](const Material& material) {
        // ptmField: monomials 3; rgb: layer base 1, 5 layer offsets, 6 fetches, 5 multiply-adds
        // (10) = 19 ALU, 6 TEX; luminance: layer addresses 3, 5 multiply-adds (10), colour
        // multiply 1 = 17 ALU, 3 TEX (the colour model and the view model are compiled in:
        // PtmMaterial::shaderDefines, no test). btfEvaluate: the final max 1; views=all adds the
        // view lookup and per blended view (3) loop 2, weight test 1, weighted add 2.
        const PtmMaterial& m = static_cast<const PtmMaterial&>(material);
        const bool luminance = m.shape().luminance;
        const int fieldAlu = luminance ? 17 : 19, fieldTex = luminance ? 3 : 6;
        const std::string variant = luminance ? "luminance" : "rgb";
        if (!m.shape().perView)
            return ShaderCost::ofEvaluate(1 + fieldAlu, fieldTex,
                                          "ALU " + std::to_string(1 + fieldAlu) + ", TEX " +
                                              std::to_string(fieldTex) + " (" + variant +
                                              ", front view)");
        const DirectionLookup::Cost v = m.viewLookup().cost();
        const int alu = 1 + 3 * (5 + fieldAlu), tex = 3 * fieldTex;
        return ShaderCost::ofEvaluate(v.alu + alu, v.tex + tex,
                                      "ALU " + std::to_string(alu) + "+L, TEX " +
                                          std::to_string(tex) + "+T (" + variant +
                                          ", views=all; L = " + std::to_string(v.alu) +
                                          ", T = " + std::to_string(v.tex) + ": the view lookup)");
    };
    m.order = 80;
    m.fitWorkingSet = 0.75;  // per-view least squares
    ForeignFileFormat ptmFile;
    ptmFile.extension = ".ptm";
    ptmFile.description =
        "Polynomial Texture Map file (PTM_1.2; PTM_FORMAT_RGB, _LRGB, _JPEG_RGB, _JPEG_LRGB): "
        "RTIBuilder's, "
        "RTIViewer's";
    ptmFile.read = [](const std::string& path) -> osg::ref_ptr<Material> {
        return readPtmFile(path);
    };
    ptmFile.write = [](const Material& material, const std::string& path) {
        const PtmQuantisation q = writePtmFile(static_cast<const PtmMaterial&>(material), path);
        return "8-bit coefficients: largest change " + floatText(float(q.largestCoefficientError)) +
               " (largest step " + floatText(float(q.largestStep)) + ")";
    };
    ptmFile.info = [](const std::string& path) {
        const PtmFileHeader h = parsePtmHeader(path, readWholeFile(path), false);
        std::string text = "PTM_1.2 " + h.format + ", " + std::to_string(h.width) + "x" +
                           std::to_string(h.height) + "\nscales:";
        for (const float s : h.scale) text += " " + floatText(s);
        text += "\nbiases:";
        for (const int b : h.bias) text += " " + std::to_string(b);
        return text;
    };
    m.foreignFiles.push_back(std::move(ptmFile));
    // relight's web layout, whatever its type (materials/RelightFolder.h): the folder's info.json.
    // Registered here, the RTI field's first basis; each type's method reads its own.
    ForeignFileFormat relightFolder;
    relightFolder.extension = "info.json";
    relightFolder.description =
        "relight's web layout as OpenLIME loads it (info.json + plane_N.jpg or deep-zoom "
        "pyramids; types ptm, hsh (colorspaces rgb, lrgb), rbf and bilinear (mrgb, mycc))";
    relightFolder.read = [](const std::string& path) { return readRelightMaterial(path); };
    relightFolder.info = [](const std::string& path) { return relightInfo(path); };
    // Written for every method that registered a relight writer (RelightLayoutWriter.h).
    relightFolder.methods = [] { return relightWriterMethods(); };
    relightFolder.write = [](const Material& material, const std::string& path) {
        return writeRelightLayout(material, path);
    };
    m.foreignFiles.push_back(std::move(relightFolder));
    return m;
}());
const bool kRelightPtmWriter =
    registerRelightWriter("ptm", [](const Material& material, const std::string& path) {
        return relightModelOfPtm(static_cast<const PtmMaterial&>(material), path);
    });
const bool kRelightPtm = registerRelightType(
    "ptm", [](const std::string& path, const RelightPlanes& planes) -> osg::ref_ptr<Material> {
        return ptmMaterialFromRelight(path, planes);
    });
}  // namespace

}  // namespace osgBTF

// StoredValues (materials/StoredValues.h): a model's array held as its file stores it. Expected
// values are worked out by hand from the formats: 8-bit fixed point k / 255 and IEEE half floats
// (10 mantissa bits: in [0.25, 0.5) the step is 2^-12).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/Error.h"
#include "materials/StoredValues.h"

using namespace osgBTF;

namespace OSGBTF_TEST_FILE {

Imath::half halfFromBits(unsigned short bits) {
    Imath::half h;
    h.setBits(bits);
    return h;
}

TEST(StoredValues, ATextureOfTheWrongShapeIsRefused) {
    const StoredValues values(MaterialTexture::Half, 5);
    try {
        values.texture("weights", 2, 2, 1, 1);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "texture 'weights': 5 values do not fill its dimensions");
    }
}

TEST(StoredValues, WritesRoundAsTheFileStores) {
    StoredValues bytes(MaterialTexture::UNorm8, 5);
    const float eightBit[] = {0.5f, -0.2f, 1.7f, std::numeric_limits<float>::quiet_NaN(), 0.2f};
    bytes.write(0, eightBit, 5);
    EXPECT_EQ(bytes[0], 128.0f / 255.0f);  // 127.5 rounds up
    EXPECT_EQ(bytes[1], 0.0f);
    EXPECT_EQ(bytes[2], 1.0f);
    EXPECT_EQ(bytes[3], 0.0f);            // no NaN in 8 bits
    EXPECT_EQ(bytes[4], 51.0f / 255.0f);  // 0.2 * 255 = 51 exactly
    EXPECT_EQ(bytes.bytes(), 5u);

    StoredValues halves(MaterialTexture::Half, 4);
    halves.set(0, 1.0f / 3.0f);
    halves.set(1, 1e6f);
    halves.set(2, -1e6f);
    halves.set(3, std::numeric_limits<float>::quiet_NaN());
    EXPECT_EQ(halves[0], 1365.0f / 4096.0f);  // 1/3 = 1365.33 steps of 2^-12
    EXPECT_EQ(halves[1], 65504.0f);           // the largest finite half
    EXPECT_EQ(halves[2], -65504.0f);
    EXPECT_TRUE(std::isnan(halves[3]));
    EXPECT_FALSE(halves.allFinite());
    EXPECT_EQ(halves.bytes(), 8u);

    StoredValues floats(MaterialTexture::Float, 1, 1.0f / 3.0f);
    EXPECT_EQ(floats[0], 1.0f / 3.0f);
    EXPECT_EQ(floats.bytes(), 4u);
    EXPECT_EQ(StoredValues::round(MaterialTexture::Half, 1.0f / 3.0f), 1365.0f / 4096.0f);
    EXPECT_EQ(StoredValues::round(MaterialTexture::UNorm8, 0.5f), 128.0f / 255.0f);
}

TEST(StoredValues, TakesAFileTextureAsStoredAndLeavesItEmpty) {
    MaterialTexture eightBit{"rho", 3, 1, 1, 1, MaterialTexture::UNorm8, {}};
    eightBit.bytes = {0, 51, 255};
    const StoredValues rho = StoredValues::take(eightBit, MaterialTexture::UNorm8);
    EXPECT_EQ(rho.kind(), MaterialTexture::UNorm8);
    EXPECT_EQ(rho.floats(), (std::vector<float>{0.0f, 51.0f / 255.0f, 1.0f}));
    EXPECT_TRUE(eightBit.bytes.empty() && eightBit.data.empty() && eightBit.halves.empty());

    // 0x3C00 = 1, 0xC000 = -2, 0x3555 = 1365 / 4096.
    MaterialTexture half{"lobes", 3, 1, 1, 1, MaterialTexture::Half, {}};
    half.halves = {halfFromBits(0x3C00), halfFromBits(0xC000), halfFromBits(0x3555)};
    const StoredValues lobes = StoredValues::take(half, MaterialTexture::Half);
    EXPECT_EQ(lobes.floats(), (std::vector<float>{1.0f, -2.0f, 1365.0f / 4096.0f}));
    EXPECT_TRUE(half.halves.empty());

    // Values held as floats (a method that unpacked them) are rounded into the stored kind, and a
    // texture of another kind is converted.
    MaterialTexture unpacked{"scale", 2, 1, 1, 1, MaterialTexture::Half, {1.0f / 3.0f, 0.5f}};
    const StoredValues scale = StoredValues::take(unpacked, MaterialTexture::Half);
    EXPECT_EQ(scale.floats(), (std::vector<float>{1365.0f / 4096.0f, 0.5f}));
    MaterialTexture other{"rhoD", 2, 1, 1, 1, MaterialTexture::Half, {}};
    other.halves = {halfFromBits(0x3800), halfFromBits(0x3C00)};  // 0.5, 1
    const StoredValues rhoD = StoredValues::take(other, MaterialTexture::UNorm8);
    EXPECT_EQ(rhoD.kind(), MaterialTexture::UNorm8);
    EXPECT_EQ(rhoD.floats(), (std::vector<float>{128.0f / 255.0f, 1.0f}));
}

TEST(StoredValues, ATextureRoundTripsAndEqualityComparesStoredValues) {
    StoredValues values(MaterialTexture::Half, 6);
    for (std::size_t i = 0; i < values.size(); ++i) values.set(i, 0.1f * float(i) - 0.2f);
    MaterialTexture t = values.texture("t", 3, 1, 1, 2);
    EXPECT_EQ(t.halves.size(), 6u);
    EXPECT_TRUE(t.data.empty());
    EXPECT_EQ(StoredValues::take(t, MaterialTexture::Half), values);

    StoredValues floats(MaterialTexture::Float, 6);
    for (std::size_t i = 0; i < floats.size(); ++i) floats.set(i, values[i]);
    EXPECT_EQ(floats.floats(), values.floats());
    EXPECT_NE(floats, values);  // the same numbers, stored differently

    StoredValues nan(MaterialTexture::Half, 1, std::numeric_limits<float>::quiet_NaN());
    EXPECT_EQ(nan, nan);  // bitwise: a file that holds a NaN reads back equal
}

}  // namespace OSGBTF_TEST_FILE

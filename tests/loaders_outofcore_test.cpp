// Captures too large for memory (loaders/OutOfCoreImageSet.h): the photos decoded once to disk
// and read back in blocks give exactly the values of the in-memory reader, every method fits the
// same material from them (bit for bit: same values, same blocks of the same products), a tiny
// memory limit picks the out-of-core path on its own, and the memory limit is one budget (data
// already held counts), refused with a message that says what holds it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <random>

#include <osg/Image>
#include <osgDB/WriteFile>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "core/MipPyramid.h"
#include "fit/MipMapping.h"
#include "loaders/LoadBtf.h"
#include "loaders/OutOfCoreImageSet.h"
#include "loaders/Rti.h"
#include "materials/MethodRegistry.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using test::errorOf;

namespace {

constexpr int kWidth = 37, kHeight = 23, kLights = 9;

class MemoryLimitGuard {
public:
    MemoryLimitGuard() : _saved(memoryLimit()) {}
    ~MemoryLimitGuard() { setMemoryLimit(_saved); }

private:
    std::uint64_t _saved;
};

/** A small RTI set of random photos: 8-bit PNGs (or 16-bit ones), lights spread over the
 *  hemisphere, written by OSG's PNG writer. Odd sizes: bands and mip levels that do not divide. */
void writeCapture(const test::TempDir& dir, bool sixteenBit) {
    std::mt19937 random(7);
    std::string lp = std::to_string(kLights) + "\n";
    for (int l = 0; l < kLights; ++l) {
        osg::ref_ptr<osg::Image> image = new osg::Image;
        image->allocateImage(kWidth, kHeight, 1, GL_RGB,
                             sixteenBit ? GL_UNSIGNED_SHORT : GL_UNSIGNED_BYTE);
        const std::size_t values = std::size_t(kWidth) * kHeight * 3;
        for (std::size_t i = 0; i < values; ++i) {
            if (sixteenBit)
                reinterpret_cast<std::uint16_t*>(image->data())[i] =
                    std::uint16_t(random() % 65536);
            else
                image->data()[i] = static_cast<unsigned char>(random() % 256);
        }
        const std::string name = "photo" + std::to_string(l) + ".png";
        ASSERT_TRUE(osgDB::writeImageFile(*image, dir.file(name)));
        const float a = 6.2831853f * float(l) / kLights, r = 0.2f + 0.07f * float(l);
        lp += name + " " + std::to_string(r * std::cos(a)) + " " + std::to_string(r * std::sin(a)) +
              " " + std::to_string(std::sqrt(1.0f - r * r)) + "\n";
    }
    test::writeTextFile(dir.file("capture.lp"), lp);
}

LoadOptions placed(LoadOptions::Placement placement) {
    LoadOptions options;
    options.placement = placement;
    return options;
}

}  // namespace

TEST(OutOfCore, ReadsGiveExactlyTheInMemoryValues) {
    for (const bool sixteenBit : {false, true}) {
        const test::TempDir dir;
        writeCapture(dir, sixteenBit);
        const std::string lp = dir.file("capture.lp");
        const MeasuredBtf memory = loadMeasuredBtf(lp);
        const std::unique_ptr<BtfSource> disk =
            openBtfSource(lp, placed(LoadOptions::Placement::Disk));
        ASSERT_FALSE(disk->inMemory());
        ASSERT_EQ(disk->width(), kWidth);
        ASSERT_EQ(disk->height(), kHeight);
        ASSERT_EQ(disk->lightCount(), std::size_t(kLights));
        EXPECT_EQ(disk->decoding, "sRGB");
        // 8-bit photos are kept as their bytes (3 per texel and photo), 16-bit ones as floats.
        const auto* set = dynamic_cast<const OutOfCoreImageSet*>(disk.get());
        ASSERT_NE(set, nullptr);
        EXPECT_EQ(set->diskBytes(),
                  std::uint64_t(kWidth) * kHeight * kLights * 3 * (sixteenBit ? 4 : 1));

        const std::size_t texels = memory.texelCount(), perTexel = memory.imageCount() * 3;
        std::vector<float> a(texels * 3), b(texels * 3);
        for (std::size_t i = 0; i < memory.imageCount(); ++i) {
            memory.readImages(i, 1, a.data());
            disk->readImages(i, 1, b.data());
            ASSERT_EQ(a, b) << "image " << i;
        }
        // Every texel in order (dense reads), and a scattered unsorted few (sparse reads).
        std::vector<float> all(texels * perTexel), allDisk(texels * perTexel);
        memory.readAbrdfRange(0, texels, all.data());
        disk->readAbrdfRange(0, texels, allDisk.data());
        EXPECT_EQ(all, allDisk);
        const std::vector<std::size_t> few = {texels - 1, 3, 500, 2 * kWidth + 5, 0};
        std::vector<float> x(few.size() * perTexel), y(few.size() * perTexel);
        memory.readAbrdfs(few.data(), few.size(), x.data());
        disk->readAbrdfs(few.data(), few.size(), y.data());
        EXPECT_EQ(x, y);
    }
}

// The mip-map atlas of a capture on disk keeps its coarse levels in a scratch file built in one
// pass; what it reads equals the atlas of the capture in memory (levels summed from the base) and
// the atlas's images, bit for bit, in order and scattered.
TEST(OutOfCore, TheMipAtlasOfACaptureOnDiskReadsAsInMemory) {
    const test::TempDir dir;
    writeCapture(dir, false);
    const std::string lp = dir.file("capture.lp");
    const MeasuredBtf memory = loadMeasuredBtf(lp);
    const std::unique_ptr<BtfSource> disk = openBtfSource(lp, placed(LoadOptions::Placement::Disk));
    const MipAtlasSource a(memory), b(*disk);
    const std::size_t texels = a.texelCount(), perTexel = a.imageCount() * 3;
    std::vector<float> fromMemory(texels * perTexel), fromDisk(texels * perTexel);
    a.readAbrdfRange(0, texels, fromMemory.data());
    b.readAbrdfRange(0, texels, fromDisk.data());
    EXPECT_EQ(fromMemory, fromDisk);
    std::vector<float> images(a.imageCount() * texels * 3);
    b.readImages(0, a.imageCount(), images.data());
    for (std::size_t t = 0; t < texels; ++t)
        for (std::size_t i = 0; i < a.imageCount(); ++i)
            for (std::size_t c = 0; c < 3; ++c)
                ASSERT_EQ(images[(i * texels + t) * 3 + c], fromDisk[t * perTexel + i * 3 + c])
                    << "texel " << t;
    // Scattered, unsorted, across levels: the top level's one texel, a level-1 texel, a base one.
    const MipLayout& layout = a.layout();
    const MipLevel& top = layout.levels().back();
    const MipLevel& one = layout.levels()[1];
    const std::vector<std::size_t> few = {
        std::size_t(top.y) * std::size_t(a.width()) + std::size_t(top.x),
        std::size_t(one.y + 3) * std::size_t(a.width()) + std::size_t(one.x + 2), 7};
    std::vector<float> x(few.size() * perTexel), y(few.size() * perTexel);
    a.readAbrdfs(few.data(), few.size(), x.data());
    b.readAbrdfs(few.data(), few.size(), y.data());
    EXPECT_EQ(x, y);
    for (std::size_t k = 0; k < few.size(); ++k)
        EXPECT_EQ(std::vector<float>(y.begin() + std::ptrdiff_t(k * perTexel),
                                     y.begin() + std::ptrdiff_t((k + 1) * perTexel)),
                  std::vector<float>(fromDisk.begin() + std::ptrdiff_t(few[k] * perTexel),
                                     fromDisk.begin() + std::ptrdiff_t((few[k] + 1) * perTexel)));
}

// Every registered method fits the same model from the photos on disk as from memory: compared
// texel by texel through the CPU evaluation of what each stored, exactly. Mip-mapped as `btf fit`
// fits by default (the atlas reads footprints across blocks of the out-of-core source).
class OutOfCoreFit : public ::testing::TestWithParam<std::string> {};

TEST_P(OutOfCoreFit, GivesTheInMemoryMaterialBitForBit) {
    const MethodInfo& method = findMethod(GetParam());
    if (!method.fit) GTEST_SKIP() << method.name << " has no fitter in this build";
    FitOptions options;
    for (const auto& [key, value] : std::map<std::string, std::string>{{"components", "3"},
                                                                       {"clusters", "4"},
                                                                       {"lobes", "1"},
                                                                       {"iterations", "5"},
                                                                       {"steps", "50"}})
        for (const OptionSpec& spec : method.options)
            if (spec.name == key) options.set(key, value);
    const test::TempDir dir;
    writeCapture(dir, false);
    const std::string lp = dir.file("capture.lp");
    const std::unique_ptr<BtfSource> memory =
        openBtfSource(lp, placed(LoadOptions::Placement::Memory));
    const std::unique_ptr<BtfSource> disk = openBtfSource(lp, placed(LoadOptions::Placement::Disk));
    ASSERT_TRUE(memory->inMemory());
    ASSERT_FALSE(disk->inMemory());
    for (const bool mipMapped : {false, true}) {
        const osg::ref_ptr<Material> a =
            mipMapped ? fitMipMapped(method, *memory, options) : method.fit(*memory, options);
        const osg::ref_ptr<Material> b =
            mipMapped ? fitMipMapped(method, *disk, options) : method.fit(*disk, options);
        ASSERT_EQ(a->width(), b->width());
        ASSERT_EQ(a->height(), b->height());
        const std::size_t texels = std::size_t(a->width()) * std::size_t(a->height());
        const std::size_t values = memory->imageCount() * 3;
        std::vector<float> x(values), y(values);
        std::size_t differing = 0;
        for (std::size_t t = 0; t < texels; ++t) {
            a->evaluateMeasured(t, x.data());
            b->evaluateMeasured(t, y.data());
            differing += x != y;
        }
        EXPECT_EQ(differing, 0u) << method.name << (mipMapped ? " mip-mapped" : "");
    }
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, OutOfCoreFit, ::testing::ValuesIn(methodNamesInOrder()),
                         [](const auto& info) {
                             std::string name = info.param;
                             std::replace(name.begin(), name.end(), '-', '_');
                             return name;
                         });

TEST(OutOfCore, ATinyMemoryLimitKeepsTheCaptureOnDisk) {
    const MemoryLimitGuard guard;
    const test::TempDir dir;
    writeCapture(dir, false);
    const std::string lp = dir.file("capture.lp");
    // The floats take 37 x 23 x 9 x 12 = 91,908 bytes: in memory under a limit of 4x that.
    setMemoryLimit(4 * 91908);
    EXPECT_TRUE(openBtfSource(lp)->inMemory());
    EXPECT_FALSE(rtiCaptureOnDisk(kWidth, kHeight, kLights, LoadOptions{}));
    setMemoryLimit(4 * 91908 - 4);
    EXPECT_TRUE(rtiCaptureOnDisk(kWidth, kHeight, kLights, LoadOptions{}));
    EXPECT_FALSE(openBtfSource(lp)->inMemory());
    // Told to keep it in memory, it is, and says what it holds; on disk it holds nothing.
    const std::unique_ptr<BtfSource> held =
        openBtfSource(lp, placed(LoadOptions::Placement::Memory));
    EXPECT_EQ(held->residentBytes(), 91908u);
    EXPECT_EQ(openBtfSource(lp)->residentBytes(), 0u);
    // Told to keep it in memory over the limit: refused before a photo is decoded, with the way
    // out that needs no more memory.
    setMemoryLimit(80000);
    EXPECT_EQ(errorOf([&] { openBtfSource(lp, placed(LoadOptions::Placement::Memory)); }),
              lp + ": an RTI capture of 37x23 pixels x 9 photos: needs 89.8 KiB in memory, more "
                   "than the memory limit of 78.1 KiB (keep it on disk with --storage disk, or "
                   "raise the limit with --memory-limit or OSGBTF_MEMORY_LIMIT)");
}

TEST(OutOfCore, TheHeader) {
    const test::TempDir dir;
    writeCapture(dir, true);
    const RtiCaptureHeader h = readRtiCaptureHeader(dir.file("capture.lp"));
    EXPECT_EQ(h.width, kWidth);
    EXPECT_EQ(h.height, kHeight);
    EXPECT_FALSE(h.rawBytes);
    EXPECT_EQ(h.lights.size(), std::size_t(kLights));
    EXPECT_EQ(h.decoding, "sRGB");
}

// A fit's allocations count together with the measured values the source holds in memory
// (before, each allocation was checked alone, and a 12.7-megapixel capture's 11 GB of floats plus
// a ptm/hsh fit's 11 GB copy of its images passed a 17.6 GB limit, to the OOM killer).
TEST(MemoryBudget, AFitCountsWhatItsSourceHolds) {
    const MemoryLimitGuard guard;
    setMemoryLimit(std::uint64_t(1) << 20);
    const MeasuredBtf held(100, 100, DirectionSet("v", {{0, 0}}), DirectionSet("l", {{0, 0}}));
    EXPECT_EQ(held.residentBytes(), 120000u);
    EXPECT_EQ(errorOf([&] { checkMemoryBeside(held, 1000000, "a fit"); }),
              "a fit: needs 976.6 KiB beside the 117.2 KiB of measured values held in memory, "
              "more than the memory limit of 1.0 MiB together (raise it with --memory-limit or "
              "OSGBTF_MEMORY_LIMIT, or keep an RTI capture on disk with --storage disk)");
    EXPECT_EQ(errorOf([&] { checkMemoryBeside(held, (1 << 20) - 120000, "a fit"); }), "no error");
    // Alone over the limit: checkMemory's own message.
    EXPECT_EQ(errorOf([&] { checkMemoryBeside(held, 2 << 20, "a fit"); }),
              "a fit: needs 2.0 MiB, more than the memory limit of 1.0 MiB (raise it with "
              "--memory-limit or OSGBTF_MEMORY_LIMIT)");
    // What a hsh fit of that data would hold beside it (model + one view's images) is refused.
    FitOptions none;
    const std::string error = errorOf([&] { findMethod("hsh").fit(held, none); });
    EXPECT_EQ(error.rfind("hsh: the model and the images of the views fitted at once: needs ", 0),
              0u)
        << error;
}

TEST(OutOfCore, NoRoomOnDiskIsAClearError) {
    const test::TempDir dir;
    writeCapture(dir, false);
    // /dev/full's folder is not a place to write; a missing folder cannot be measured.
    const char* saved = std::getenv("OSGBTF_CACHE_DIR");
    const std::string savedValue = saved ? saved : "";
    setenv("OSGBTF_CACHE_DIR", dir.file("missing").c_str(), 1);
    const std::string error = errorOf(
        [&] { openBtfSource(dir.file("capture.lp"), placed(LoadOptions::Placement::Disk)); });
    if (saved)
        setenv("OSGBTF_CACHE_DIR", savedValue.c_str(), 1);
    else
        unsetenv("OSGBTF_CACHE_DIR");
    // Named by the folder of the photos.
    EXPECT_EQ(error, dir.file("missing") + ": cannot use it for the decoded photos of " +
                         dir.path().string() + ": No such file or directory");
}

// The tool: `btf info` of a capture kept on disk reads headers only (stats on request), `btf fit`
// fits from the disk copy, and a capture that does not fit in memory as asked is refused with
// the size and the way out.
TEST(OutOfCore, TheToolDescribesAndFitsACaptureOnDisk) {
    const test::TempDir dir;
    writeCapture(dir, false);
    const std::string btf = test::shellQuote(test::builtTool("btf")),
                      lp = test::shellQuote(dir.file("capture.lp"));
    test::CommandResult r = test::runCommand(btf + " info " + lp + " --storage disk 2>&1");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("texels:   37 x 23 (0.0 megapixels)"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("storage:  disk: 22.4 KiB decoded into"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("stats:    not computed (--stats decodes every photo)"),
              std::string::npos)
        << r.output;
    r = test::runCommand(btf + " --no-progress info " + lp + " --storage disk --stats 2>&1");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("non-finite: 0 NaN, 0 Inf"), std::string::npos) << r.output;

    const std::string out = dir.file("h.btfmat");
    r = test::runCommand(btf + " --no-progress fit " + lp + " --storage disk -m hsh -o " +
                         test::shellQuote(out) + " 2>&1");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(std::filesystem::exists(out));

    r = test::runCommand(btf + " --no-progress --memory-limit 50K fit " + lp +
                         " --storage float -m hsh -o " + test::shellQuote(dir.file("x.btfmat")) +
                         " 2>&1");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find(dir.file("capture.lp") +
                            ": an RTI capture of 37x23 pixels x 9 photos: needs 89.8 KiB "
                            "in memory, more than the memory limit of 50.0 KiB (keep it on "
                            "disk with --storage disk"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.btfmat")));
}

}  // namespace OSGBTF_TEST_FILE

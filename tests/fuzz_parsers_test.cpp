// The parser fuzz harnesses (common/fuzz/fuzz_targets.hpp) on fixed seeds, reproducible in CI:
// every checked-in seed of tests/fuzz/<name>/ is accepted by its reader (so the seeds reach the
// parsers, and a cache format change that makes them stale is noticed: rerun make_fuzz_seeds),
// and a few thousand deterministic mutations of them are each rejected with an error or accepted
// as usable data, never crash (run under OCC_SANITIZE for memory errors). A property the harness
// checks that fails aborts the test binary with the property's name. The long runs are libFuzzer's
// (OCC_LIBFUZZER).
#include <unistd.h>

#include <cstring>
#include <filesystem>

#include <gtest/gtest.h>

#include "common/fuzz/fuzz_targets.hpp"
#include "common/lod/lod_cache.hpp"
#include "common/mapped_file.hpp"
#include "common/scene/scene_cache.hpp"

using namespace occ::fuzz;

namespace {

std::string seed_dir(const Target& t) { return std::string(OCC_SOURCE_DIR) + "/tests/fuzz/" + t.name; }

class ParserFuzz : public ::testing::TestWithParam<const char*> {
 protected:
  const Target& target() const { return *find_target(GetParam()); }
};

TEST_P(ParserFuzz, CheckedInSeedsAreAccepted) {
  const auto seeds = read_seeds(seed_dir(target()));
  ASSERT_GE(seeds.size(), 1u) << seed_dir(target());
  for (size_t i = 0; i < seeds.size(); ++i)
    EXPECT_EQ(target().run(seeds[i]), Verdict::Accepted)
        << target().name << " seed " << i << " (stale? rerun make_fuzz_seeds " << OCC_SOURCE_DIR << "/tests/fuzz)";
}

TEST_P(ParserFuzz, MutatedSeedsAreRejectedOrUsable) {
  const auto seeds = read_seeds(seed_dir(target()));
  ASSERT_GE(seeds.size(), 1u);
  std::mt19937_64 rng(0xf022 + std::string_view(target().name).size());
  size_t accepted = 0, rejected = 0;
  constexpr int kInputs = 3000;
  std::vector<uint8_t> b;
  for (int i = 0; i < kInputs; ++i) {
    // Mostly one to three edits of a seed; every fourth input carries on from the last one.
    if (i % 4 != 3 || b.empty()) b = seeds[rng() % seeds.size()];
    mutate(b, seeds[rng() % seeds.size()], rng);
    (target().run(b) == Verdict::Accepted ? accepted : rejected) += 1;
  }
  EXPECT_EQ(accepted + rejected, size_t(kInputs));
  EXPECT_GT(rejected, size_t(kInputs) / 10) << "the mutations reach the readers' checks";
  EXPECT_GT(accepted, 0u) << "some mutations stay valid: the readers' accepting paths run too";
}

INSTANTIATE_TEST_SUITE_P(Readers, ParserFuzz,
                         ::testing::Values("gltf", "camera_path", "scene_cache", "lod_cache", "ply", "obj", "web_input"),
                         [](const auto& info) { return std::string(info.param); });

TEST(ParserFuzz, EveryHarnessIsTested) {
  EXPECT_EQ(targets().size(), 7u);
  for (const Target& t : targets()) EXPECT_EQ(find_target(t.name), &t);
  EXPECT_EQ(find_target("nope"), nullptr);
}

// What the harnesses found, kept: a LOD cache whose item slot is 2^32 - 1 (the range check's
// slot + 1 wrapped to 0 in 32 bits, and the renderer read far past the cluster LODs).
TEST(ParserFuzzFindings, LodCacheItemSlotAtTheTopOfUint32IsRejected) {
  std::vector<uint8_t> b = read_seeds(seed_dir(*find_target("lod_cache")))[0];
  size_t off = occ::CacheHeader::kSize;
  auto u64 = [&] {
    uint64_t v = 0;
    std::memcpy(&v, b.data() + off, 8);
    off += 8;
    return v;
  };
  off += u64() * 64;  // the cluster LOD records: origin, error, counts of positions, normals, objects, indices
  ASSERT_EQ(u64(), fixture().hierarchy.items().size());  // the item slot table
  const uint32_t top = 0xffffffffu;
  std::memcpy(b.data() + off, &top, 4);
  EXPECT_EQ(find_target("lod_cache")->run(b), Verdict::Rejected);  // the harness fits size and checksum
}

// A scene cache whose material names a texture the file does not have.
TEST(ParserFuzzFindings, SceneCacheMaterialTextureOutOfRangeIsRejected) {
  occ::Scene s = fixture().scene;
  occ::Material m;
  m.base_color_texture = 3;
  s.materials.push_back(m);
  s.meshes[0].material = 0;
  const occ::Hierarchy h = occ::Hierarchy::build(s, kFixtureBuild);
  const std::string path = (std::filesystem::temp_directory_path() / ("occ_fuzz_find_" + std::to_string(::getpid()) + ".scene")).string();
  ASSERT_FALSE(occ::save_scene_cache(path, 1, s, h).has_value());
  std::string why;
  EXPECT_FALSE(occ::load_scene_cache(path, 1, &why).has_value());
  EXPECT_EQ(why, "material 0: texture out of range");
  std::filesystem::remove(path);
}

}  // namespace

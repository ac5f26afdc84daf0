// Enclosures (common/cull/enclosure.hpp): what is sealed inside closed convex opaque solids, when
// that hides it from a camera, and that HC then neither tests nor returns it.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "common/cull/culling.hpp"
#include "common/cull/enclosure.hpp"
#include "common/scene/scene_shapes.hpp"
#include "common/scene/structures.hpp"

using namespace occ;

namespace {

uint32_t add(Scene& s, Mesh m) {
  s.meshes.push_back(std::move(m));
  return uint32_t(s.meshes.size() - 1);
}

void put(Scene& s, uint32_t mesh, glm::dvec3 at, glm::dvec3 size, const std::string& name) {
  s.objects.push_back({mesh, glm::scale(glm::translate(glm::dmat4(1.0), at), size), name});
}

// The leaf holding object `name`'s item.
uint32_t leaf_of(const Scene& s, const Hierarchy& h, const std::string& name) {
  for (uint32_t id = 0; id < h.size(); ++id) {
    const HNode& n = h.node(id);
    if (n.leaf() && n.item_count == 1 && s.objects[h.items()[n.first_item].object].name == name) return id;
  }
  ADD_FAILURE() << "no leaf for " << name;
  return 0;
}

// Solids (4 x 2 x 4 at x = 0, 10, 20, ...) each with a cube well inside, and the cases that must
// not seal it: an open box, a cube touching a face, one poking out, two boxes in one mesh (not
// convex), a BLEND box, a single-sided box wound inwards, a single-sided box mirrored.
Scene solids_scene() {
  Scene s;
  Material glass;
  glass.alpha_mode = AlphaMode::Blend;
  Material single;
  single.double_sided = false;
  s.materials = {glass, single};
  const uint32_t cube = add(s, box_mesh("cube", {0, 0, 0}, {1, 1, 1}));
  const uint32_t open = add(s, box_mesh("open", {0, 0, 0}, {1, 1, 1}, true));
  Mesh two = box_mesh("two boxes", {0, 0, 0}, {0.4f, 1, 1});
  const Mesh other = box_mesh("", {0.6f, 0, 0}, {1, 1, 1});
  const auto base = uint32_t(two.positions.size());
  two.positions.insert(two.positions.end(), other.positions.begin(), other.positions.end());
  two.normals.insert(two.normals.end(), other.normals.begin(), other.normals.end());
  for (uint32_t i : other.indices) two.indices.push_back(base + i);
  const uint32_t pair = add(s, two);
  Mesh blend = box_mesh("blend", {0, 0, 0}, {1, 1, 1});
  blend.material = 0;
  const uint32_t blended = add(s, blend);
  Mesh inward = box_mesh("inward", {0, 0, 0}, {1, 1, 1});
  for (size_t t = 0; t < inward.indices.size(); t += 3) std::swap(inward.indices[t + 1], inward.indices[t + 2]);
  inward.material = 1;
  const uint32_t inwards = add(s, inward);
  Mesh outward = box_mesh("single-sided", {0, 0, 0}, {1, 1, 1});
  outward.material = 1;
  const uint32_t single_sided = add(s, outward);

  const glm::dvec3 solid(4, 2, 4), inner(1, 0.5, 1);
  auto pair_of = [&](int k, uint32_t solid_mesh, glm::dvec3 inner_at, const std::string& name) {
    put(s, solid_mesh, {10.0 * k, 0, 0}, solid, name + " solid");
    put(s, cube, glm::dvec3(10.0 * k, 0, 0) + inner_at, inner, name);
  };
  pair_of(0, cube, {1.5, 0.75, 1.5}, "sealed");
  pair_of(1, open, {1.5, 0.75, 1.5}, "in an open box");
  pair_of(2, cube, {3.0, 0.75, 1.5}, "touching a face");
  pair_of(3, cube, {3.5, 0.75, 1.5}, "poking out");
  pair_of(4, pair, {0.2, 0.75, 1.5}, "in a mesh of two boxes");
  pair_of(5, blended, {1.5, 0.75, 1.5}, "in glass");
  pair_of(6, inwards, {1.5, 0.75, 1.5}, "in a box wound inwards");
  pair_of(7, single_sided, {1.5, 0.75, 1.5}, "in a single-sided box");
  // Mirrored: x scaled by -4 (the box spans x 84..80); single-sided: its front faces turn inwards.
  s.objects.push_back({single_sided, glm::scale(glm::translate(glm::dmat4(1.0), {84, 0, 0}), {-4, 2, 4}),
                       "mirrored single-sided solid"});
  put(s, cube, {81.5, 0.75, 1.5}, inner, "in a mirrored single-sided box");
  // Mirrored and double-sided: seals.
  s.objects.push_back({cube, glm::scale(glm::translate(glm::dmat4(1.0), {94, 0, 0}), {-4, 2, 4}), "mirrored solid"});
  put(s, cube, {91.5, 0.75, 1.5}, inner, "in a mirrored box");
  return s;
}

}  // namespace

TEST(Enclosures, SealOnlyWhatLiesStrictlyInsideAClosedConvexOpaqueSolid) {
  Scene s = solids_scene();
  const Hierarchy h = Hierarchy::build(s, {});
  const Enclosures e = Enclosures::find(s, h);
  EXPECT_TRUE(e.sealed(leaf_of(s, h, "sealed")));
  EXPECT_TRUE(e.sealed(leaf_of(s, h, "in a single-sided box")));
  EXPECT_TRUE(e.sealed(leaf_of(s, h, "in a mirrored box")));
  for (const char* name : {"in an open box", "touching a face", "poking out", "in a mesh of two boxes", "in glass",
                           "in a box wound inwards", "in a mirrored single-sided box", "sealed solid"})
    EXPECT_FALSE(e.sealed(leaf_of(s, h, name))) << name;
  EXPECT_EQ(e.sealed_items(), 3u);
  EXPECT_EQ(e.solids(), 3u);
  EXPECT_FALSE(e.sealed(0));  // the root holds unsealed items
}

TEST(Enclosures, HideOnlyFromOutsideWithTheMarginAPixelFractionAndTheSolidUnclipped) {
  Scene s = solids_scene();
  const Hierarchy h = Hierarchy::build(s, {});
  const Enclosures e = Enclosures::find(s, h);
  const uint32_t leaf = leaf_of(s, h, "sealed");
  auto from = [](glm::dvec3 eye, double near_dist) {
    return Camera::look_at(eye, {2, 1, 2}, {0, 1, 0}, 60, 1, near_dist, 1e6);
  };
  EXPECT_TRUE(e.hides(leaf, from({2, 8, 12}, 0.1), 512));
  EXPECT_FALSE(e.hides(leaf, from({2, 1, 2.1}, 0.01), 512)) << "eye inside the solid";
  EXPECT_FALSE(e.hides(leaf, from({2, 1, 4.05}, 0.1), 512)) << "the near plane cuts the solid";
  // The margin is 0.75: it spans under 1/64 pixel beyond about 0.75 * 64 * 512 / (2 tan 30) = 21 km.
  EXPECT_TRUE(e.hides(leaf, from({2, 1, 15e3}, 1.0), 512));
  EXPECT_FALSE(e.hides(leaf, from({2, 1, 30e3}, 1.0), 512));
  EXPECT_FALSE(e.hides(leaf_of(s, h, "poking out"), from({2, 8, 12}, 0.1), 512));
}

namespace {
struct CountingQueries : OcclusionQueries {
  std::vector<Aabb> boxes;
  uint32_t issue(const Aabb& b) override {
    boxes.push_back(b);
    return uint32_t(boxes.size() - 1);
  }
  uint64_t result(uint32_t) override { return 1; }  // everything tested shows
};
}  // namespace

TEST(Enclosures, HcNeitherTestsNorReturnsWhatTheyHide) {
  Scene s = solids_scene();
  const Hierarchy h = Hierarchy::build(s, {});
  const Enclosures e = Enclosures::find(s, h);
  const Renderables r(h, nullptr);
  const Camera cam = Camera::look_at({47, 90, 110}, {47, 1, 2}, {0, 1, 0}, 90, 1, 0.1, 1e4);
  const LodSelector sel(r, cam, 512, 0);
  size_t all = 0;
  for (bool sealed : {false, true}) {
    CountingQueries q;
    CullStats st;
    HcOptions o{.choices = {.sealed = sealed}, .enclosures = &e, .stats = &st};
    const std::vector<uint32_t> found = hardware_cull_lod(h, cam, q, sel, o);
    for (const char* name : {"sealed", "in a single-sided box", "in a mirrored box"}) {
      const uint32_t leaf = leaf_of(s, h, name);
      EXPECT_EQ(std::count(found.begin(), found.end(), leaf), sealed ? 0 : 1) << name;
      EXPECT_EQ(std::count(q.boxes.begin(), q.boxes.end(), h.node(leaf).box), sealed ? 0 : 1) << name;
    }
    if (!sealed) all = found.size();
    EXPECT_EQ(found.size(), sealed ? all - 3 : s.objects.size());
    EXPECT_EQ(st.sealed, sealed ? 3u : 0u);
  }
}

// The bridge's reinforcement lies inside its concrete with 3.75 cm or more to spare: every bar,
// stirrup and tie is sealed, no member of concrete nor the ground is.
TEST(Enclosures, EveryBarOfTheBridgeIsSealedInItsConcrete) {
  Scene s = bridge(3);
  const Hierarchy h = Hierarchy::build(s, {});
  const Enclosures e = Enclosures::find(s, h);
  uint32_t bars = 0;
  for (const Item& it : h.items()) {
    const std::string& name = s.objects[it.object].name;
    bars += name.find(" bar ") != std::string::npos || name.find("stirrup") != std::string::npos ||
            name.find(" tie ") != std::string::npos;
  }
  EXPECT_EQ(bars, s.objects.size() - 1 - 3 * 7);  // the ground and 7 members a span
  EXPECT_EQ(e.sealed_items(), bars);
  EXPECT_EQ(e.solids(), 3u * 4);  // deck, two girders and the pier hold bars; parapets and caps none
}

#include <gtest/gtest.h>

#include <array>
#include <set>

#include <glm/gtc/matrix_transform.hpp>

#include "common/scene/hierarchy.hpp"
#include "scene_fixtures.hpp"

using namespace occ;

namespace {
// A grid of unit cubes 3 apart, one mesh shared by all objects, plus one big tessellated plane mesh.
Scene grid_scene(int n, int plane_res) {
  Scene s = occtest::cube_grid(n, 3.0);
  Mesh plane;
  for (int z = 0; z <= plane_res; ++z)
    for (int x = 0; x <= plane_res; ++x) plane.positions.push_back({float(x), 0.f, float(z)});
  for (int z = 0; z < plane_res; ++z)
    for (int x = 0; x < plane_res; ++x) {
      uint32_t a = z * (plane_res + 1) + x, b = a + 1, c = a + plane_res + 1, d = c + 1;
      plane.indices.insert(plane.indices.end(), {a, c, b, b, c, d});
    }
  compute_normals(plane);
  s.meshes.push_back(plane);
  s.objects.push_back(Object{1, glm::translate(glm::dmat4(1.0), glm::dvec3(0, -1, 0)), "plane"});
  return s;
}
}  // namespace

TEST(Hierarchy, SameInputGivesSameIdsAndFingerprint) {
  Scene a = grid_scene(12, 64), b = grid_scene(12, 64);
  Hierarchy ha = Hierarchy::build(a, {}), hb = Hierarchy::build(b, {});
  EXPECT_EQ(ha.fingerprint(), hb.fingerprint());
  ASSERT_EQ(ha.size(), hb.size());
  for (size_t i = 0; i < ha.size(); ++i) EXPECT_EQ(ha.node(i).box, hb.node(i).box);
}

TEST(Hierarchy, ChangedParameterOrGeometryChangesFingerprint) {
  Scene a = grid_scene(6, 16), b = grid_scene(6, 16), c = grid_scene(6, 16);
  BuildParams p4;
  p4.arity = 4;
  c.objects[3].transform[3][0] += 0.001;
  uint64_t fa = Hierarchy::build(a, {}).fingerprint();
  EXPECT_NE(fa, Hierarchy::build(b, p4).fingerprint());
  EXPECT_NE(fa, Hierarchy::build(c, {}).fingerprint());
}

TEST(Hierarchy, IdsAreDenseBreadthFirstAndSubtreesContiguous) {
  Scene s = grid_scene(10, 8);
  Hierarchy h = Hierarchy::build(s, {});
  uint64_t tris = 0;
  for (const Item& it : h.items()) tris += it.triangles;
  EXPECT_EQ(tris, s.triangle_count());
  EXPECT_EQ(h.node(0).item_count, h.items().size());
  std::set<uint32_t> covered;
  for (uint32_t id = 0; id < h.size(); ++id) {
    const HNode& n = h.node(id);
    if (id > 0) {
      EXPECT_GE(n.depth, h.node(id - 1).depth);  // BFS: depth never decreases
    }
    if (n.leaf()) {
      EXPECT_LE(n.item_count, h.params().leaf_items);
      for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) covered.insert(i);
      continue;
    }
    EXPECT_LE(n.child_count, h.params().arity);
    uint32_t next = n.first_item, child_items = 0;
    for (uint32_t c = n.first_child; c < n.first_child + n.child_count; ++c) {
      const HNode& ch = h.node(c);
      EXPECT_EQ(ch.parent, id);
      EXPECT_EQ(ch.first_item, next);  // children partition the parent's item range in order
      next += ch.item_count;
      child_items += ch.item_count;
      EXPECT_TRUE(n.box.contains(ch.box.min) && n.box.contains(ch.box.max));
    }
    EXPECT_EQ(child_items, n.item_count);
  }
  EXPECT_EQ(covered.size(), h.items().size());
}

TEST(Hierarchy, BigMeshIsSplitIntoSpatialClusters) {
  Scene s = grid_scene(1, 100);  // plane: 20000 triangles
  BuildParams p;
  p.cluster_triangles = 1000;
  Hierarchy h = Hierarchy::build(s, p);
  const Mesh& plane = s.meshes[1];
  ASSERT_GE(plane.clusters.size(), 20u);
  double area_sum = 0;
  uint32_t indices = 0;
  for (const MeshCluster& c : plane.clusters) {
    EXPECT_LE(c.index_count / 3, 1000u);
    EXPECT_EQ(c.first_index, indices);
    indices += c.index_count;
    area_sum += c.box.extent().x * c.box.extent().z;
  }
  EXPECT_EQ(indices, plane.indices.size());
  EXPECT_LT(area_sum, 100.0 * 100.0 * 1.5);  // spatial: cluster boxes barely overlap
  EXPECT_EQ(h.items().size(), 1 + plane.clusters.size());
}

// After the split the vertices are numbered in the order the triangles first use them, and the
// triangles are the same ones (the same corner positions), cluster by cluster.
TEST(Hierarchy, ClusteredMeshNumbersVerticesInFirstUseOrder) {
  Scene s = grid_scene(1, 60);
  const Mesh before = s.meshes[1];
  std::multiset<std::array<float, 9>> triangles_before;
  auto corners = [](const Mesh& m, size_t t) {
    std::array<float, 9> c{};
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) c[size_t(3 * k + a)] = m.positions[m.indices[3 * t + size_t(k)]][a];
    return c;
  };
  for (size_t t = 0; t < before.indices.size() / 3; ++t) triangles_before.insert(corners(before, t));
  BuildParams p;
  p.cluster_triangles = 500;
  Hierarchy::build(s, p);
  const Mesh& m = s.meshes[1];
  uint32_t next = 0;
  for (uint32_t i : m.indices) {
    ASSERT_LE(i, next) << "vertex " << i << " used before vertex " << next;
    if (i == next) ++next;
  }
  EXPECT_EQ(next, m.positions.size()) << "every vertex is used";
  EXPECT_EQ(m.normals.size(), m.positions.size());
  std::multiset<std::array<float, 9>> triangles_after;
  for (size_t t = 0; t < m.indices.size() / 3; ++t) triangles_after.insert(corners(m, t));
  EXPECT_EQ(triangles_after, triangles_before);
}

TEST(Hierarchy, EmptySceneHasARootLeaf) {
  Scene s;
  Hierarchy h = Hierarchy::build(s, {});
  ASSERT_EQ(h.size(), 1u);
  EXPECT_TRUE(h.node(0).leaf());
  EXPECT_EQ(h.node(0).item_count, 0u);
}

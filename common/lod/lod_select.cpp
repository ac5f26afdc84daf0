// The renderable-id space, lod_benefit, projected_error_px and LodSelector (lod_select.hpp).
#include "common/lod/lod_select.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace occ {

Renderables::Renderables(const Hierarchy& h, const LodData* lod) : h_(h), lod_(lod), n_(uint32_t(h.size())) {
  leaf_index_.assign(h.size(), kNoNode);
  for (uint32_t id = 0; id < h.size(); ++id)
    if (h.node(id).leaf()) {
      leaf_index_[id] = uint32_t(extra_leaf_.size());
      extra_leaf_.push_back(id);
    }
  count_ = n_ + uint32_t(extra_leaf_.size()) * kLeafLodLevels;
}

uint64_t Renderables::triangles(uint32_t r) const {
  const uint32_t node = node_of(r), level = level_of(r);
  const HNode& n = h_.node(node);
  if (n.leaf()) {
    if (level == 0 || !lod_) return n.triangles;
    uint64_t t = 0;
    for (uint32_t i = n.first_item; i < n.first_item + n.item_count; ++i) t += lod_->item_lod(i, level).triangles();
    return t;
  }
  const LodMesh* m = lod_ ? lod_->hlod(node) : nullptr;
  return m ? m->triangles() : n.triangles;
}

LodBenefit lod_benefit(const LodData& lod, const Hierarchy& h) {
  Renderables r(h, &lod);
  uint64_t full = 0, leaves_coarse = 0;
  for (uint32_t id = 0; id < h.size(); ++id)
    if (h.node(id).leaf()) {
      full += h.node(id).triangles;
      leaves_coarse += r.triangles(r.id(id, kLeafLodLevels));
    }
  if (full == 0) return {};
  uint64_t below_root = 0;
  const HNode& root = h.node(0);
  if (root.leaf()) {
    below_root = leaves_coarse;
  } else {
    for (uint32_t c = root.first_child; c < root.first_child + root.child_count; ++c)
      below_root += h.node(c).leaf() ? r.triangles(r.id(c, kLeafLodLevels)) : r.triangles(c);
  }
  const uint64_t coarse = std::min({leaves_coarse, below_root, full});
  return {1.0 - double(coarse) / double(full), full - coarse};
}

double projected_error_px(double object_error, double distance, double viewport_height_px, double fovy_rad) {
  if (!(distance > 0)) return std::numeric_limits<double>::infinity();  // eye in or on the box
  if (!(object_error > 0)) return 0.0;
  const double t = std::tan(0.5 * fovy_rad);
  if (!(t > 0)) return std::numeric_limits<double>::infinity();
  return object_error * viewport_height_px / (2.0 * distance * t);
}

LodSelector::LodSelector(const Renderables& r, const Camera& cam, double viewport_height_px, double tau)
    : r_(r), h_(r.hierarchy()), cam_(cam), viewport_height_px_(viewport_height_px), tau_(tau) {}

double LodSelector::error_px(uint32_t node, uint32_t level) const {
  if (!r_.lod()) return std::numeric_limits<double>::infinity();
  const double d = std::sqrt(h_.node(node).box.distance2(cam_.eye));
  return projected_error_px(r_.lod()->error(node, level), d, viewport_height_px_, cam_.fovy_rad);
}

bool LodSelector::satisfies(uint32_t node) const {
  const HNode& n = h_.node(node);
  if (n.leaf()) return true;
  if (!(tau_ > 0) || !r_.lod() || n.item_count == 0) return false;
  return error_px(node, 0) <= tau_;
}

uint32_t LodSelector::leaf_level(uint32_t node) const {
  if (!(tau_ > 0) || !r_.lod()) return 0;
  for (uint32_t l = kLeafLodLevels; l >= 1; --l)
    if (error_px(node, l) <= tau_) return l;
  return 0;
}

uint32_t LodSelector::renderable(uint32_t node) const {
  return h_.node(node).leaf() ? r_.id(node, leaf_level(node)) : node;
}

uint32_t LodSelector::coarsest(uint32_t node) const {
  if (!(tau_ > 0) || !r_.lod()) return node;
  return h_.node(node).leaf() ? r_.id(node, kLeafLodLevels) : node;
}

void LodData::forbid_hlod(uint32_t node) { errors_[node].fill(kForbidden); }

uint32_t forbid_blended_hlods(LodData& lod, const Scene& scene, const Hierarchy& h) {
  std::vector<uint8_t> forbidden(h.size(), 0);
  for (uint32_t id = 0; id < h.size(); ++id) {
    const HNode& n = h.node(id);
    if (!n.leaf()) continue;
    bool blended = false;
    for (uint32_t i = n.first_item; i < n.first_item + n.item_count && !blended; ++i) {
      const Material* m = scene.material_of(scene.objects[h.items()[i].object].mesh);
      blended = m && m->alpha_mode == AlphaMode::Blend;
    }
    for (uint32_t p = n.parent; blended && p != kNoNode && !forbidden[p]; p = h.node(p).parent) forbidden[p] = 1;
  }
  uint32_t count = 0;
  for (uint32_t id = 0; id < h.size(); ++id)
    if (forbidden[id]) {
      lod.forbid_hlod(id);
      ++count;
    }
  return count;
}

}  // namespace occ

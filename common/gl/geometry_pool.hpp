// Geometry resident within a budget (--geometry-budget): one GL buffer of fixed size
// (the arena) holds the pieces a renderer has drawn lately — a piece is one scene mesh or one
// LOD/HLOD mesh, its vertices followed by its indices — and a piece that a draw needs and that is
// not resident is read (from the mapped cache or the CPU copy, through the Loader) and uploaded
// then, before the draw: the frame waits for it; it never draws something else instead. Room is
// made by evicting the least recently used pieces; the pieces of the current window (the draws
// being submitted) are never evicted, and when the next piece does not fit beside them the window
// ends there (the renderer draws it and starts the next one, in the same order: see
// SceneRenderer). Internal to occ_gl: SceneGpu owns one in streaming mode.
//
// Layout: the arena is counted in units of 28 bytes (one vertex): a piece of nv vertices and ni
// indices takes nv + ceil(ni / 7) units from unit u: its vertices at u (its base vertex), its
// indices right after them (first index (u + nv) * 7). With texture coordinates a second buffer
// holds 8 bytes per unit (uvs at the base vertex). Free ranges are kept by start and by size
// (best fit, merged with their neighbours).
//
// Contracts: the GL context is current for every call but stats() and the sizes.
#pragma once
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/gl/gl_api.hpp"

namespace occ {

class GeometryPool {
 public:
  static constexpr uint64_t kUnitBytes = 28;
  static constexpr uint64_t kInitialBytes = uint64_t(32) << 20;
  static constexpr uint32_t kNone = ~0u;
  struct PieceSize {
    uint64_t vertices = 0, indices = 0;
  };
  // What streaming cost so far (counted from construction; a frame takes differences).
  struct Stats {
    uint64_t uploads = 0;        // pieces uploaded because a draw needed them (waits)
    uint64_t upload_bytes = 0;
    double upload_ms = 0;        // reading and uploading them
    uint64_t evictions = 0;
    uint64_t extra_windows = 0;  // draw calls cut because their pieces did not fit together
  };
  // Fills `bytes` with piece p's vertices (kUnitBytes each) followed by its indices (u32), and
  // with uvs its texture coordinates (one per vertex). Throws for unreadable data.
  using Loader = std::function<void(uint32_t piece, std::vector<uint8_t>& bytes, std::vector<glm::vec2>* uvs)>;

  // An arena of at most budget_bytes (all pieces' units if fewer), uv buffer included. It starts
  // at kInitialBytes (a quarter of that at most) and doubles (a new buffer, the old one's contents copied over) whenever a
  // piece does not fit and the budget allows, before anything is evicted: a process pays for the
  // geometry it has drawn, up to the budget, not for the budget.
  GeometryPool(const GlApi& gl, uint64_t budget_bytes, std::vector<PieceSize> sizes, bool uvs, Loader loader);
  ~GeometryPool();
  GeometryPool(const GeometryPool&) = delete;
  GeometryPool& operator=(const GeometryPool&) = delete;

  // A new window: the pieces acquired from now on are kept until the next one.
  void begin_window();
  // Piece p resident for this window (uploaded now if it was not), evicting least recently used
  // pieces of earlier windows; false when it does not fit beside this window's pieces. Throws
  // std::runtime_error for a piece larger than the whole arena.
  bool acquire(uint32_t p);
  // A draw call was cut into one more window (stats).
  void count_extra_window() { ++stats_.extra_windows; }
  // Uploads every piece, in order, while they fit (the scene fits its budget: nothing streams).
  void preload();

  int32_t base_vertex(uint32_t p) const { return int32_t(at_[p]); }
  uint32_t first_index(uint32_t p) const { return uint32_t((at_[p] + sizes_[p].vertices) * 7); }
  bool resident(uint32_t p) const { return at_[p] != kNone; }
  GLuint buffer() const { return buffer_; }
  // Changes when the arena moved to a larger buffer (the vertex array must be bound again).
  uint32_t generation() const { return generation_; }
  GLuint uv_buffer() const { return uv_buffer_; }
  uint64_t capacity_bytes() const { return capacity_ * unit_bytes(); }  // now
  uint64_t budget_bytes() const { return max_units_ * unit_bytes(); }   // at most
  uint64_t resident_bytes() const { return used_ * unit_bytes(); }
  uint64_t total_bytes() const { return total_units_ * unit_bytes(); }  // every piece
  size_t pieces() const { return sizes_.size(); }
  const Stats& stats() const { return stats_; }

 private:
  uint64_t units_of(uint32_t p) const { return sizes_[p].vertices + (sizes_[p].indices + 6) / 7; }
  uint64_t unit_bytes() const { return kUnitBytes + (uvs_ ? 8 : 0); }
  bool allocate(uint64_t units, uint64_t* start);
  bool grow(uint64_t units);  // room for `units` more if the budget allows; false if not
  void create_buffers(uint64_t units, GLuint* buffer, GLuint* uv_buffer) const;
  void release(uint64_t start, uint64_t units);
  void evict(uint32_t p);
  void touch(uint32_t p);  // most recently used
  void unlink(uint32_t p);
  void upload(uint32_t p);
  void place(uint32_t p, uint64_t start);  // p resident from unit `start`, most recent, uploaded

  const GlApi& gl_;
  std::vector<PieceSize> sizes_;
  Loader loader_;
  bool uvs_ = false;
  GLuint buffer_ = 0, uv_buffer_ = 0;
  uint64_t capacity_ = 0, max_units_ = 0, used_ = 0, total_units_ = 0;  // units
  uint32_t generation_ = 0;
  std::vector<uint32_t> at_;                  // per piece: first unit, or kNone
  std::vector<uint32_t> window_of_;           // per piece: the window it was last acquired in
  std::vector<uint32_t> prev_, next_;         // LRU list (head: most recent)
  uint32_t head_ = kNone, tail_ = kNone;
  uint32_t window_ = 0;
  std::map<uint64_t, uint64_t> free_by_start_;          // start -> units
  std::multimap<uint64_t, uint64_t> free_by_size_;      // units -> start
  std::vector<uint8_t> staging_;
  std::vector<glm::vec2> staging_uvs_;
  Stats stats_;
};

// One line on `out` with what streaming cost a process over its run ("<who>: geometry:
// budget_mb=... pieces=... uploads=... upload_mb=... upload_ms=... evictions=... cut_calls=..."),
// nothing without a pool (everything resident).
void print_geometry_line(std::FILE* out, const std::string& who, const GeometryPool* pool);

}  // namespace occ

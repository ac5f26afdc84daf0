#include "common/gl/geometry_pool.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "common/progress.hpp"

namespace occ {

namespace {
// first_index is a u32 count of indices: (unit + vertices) * 7 must fit.
constexpr uint64_t kMaxUnits = (uint64_t(1) << 32) / 7 - 1;
}  // namespace

GeometryPool::GeometryPool(const GlApi& gl, uint64_t budget_bytes, std::vector<PieceSize> sizes, bool uvs,
                           Loader loader)
    : gl_(gl), sizes_(std::move(sizes)), loader_(std::move(loader)), uvs_(uvs) {
  for (uint32_t p = 0; p < sizes_.size(); ++p) total_units_ += units_of(p);
  max_units_ = std::min({budget_bytes / unit_bytes(), std::max<uint64_t>(total_units_, 1), kMaxUnits});
  if (max_units_ == 0) throw std::runtime_error("--geometry-budget: too small for any geometry");
  capacity_ = std::max<uint64_t>(1, std::min(max_units_ / 4, kInitialBytes / unit_bytes()));
  create_buffers(capacity_, &buffer_, &uv_buffer_);
  at_.assign(sizes_.size(), kNone);
  window_of_.assign(sizes_.size(), 0);
  prev_.assign(sizes_.size(), kNone);
  next_.assign(sizes_.size(), kNone);
  free_by_start_[0] = capacity_;
  free_by_size_.emplace(capacity_, 0);
  window_ = 1;
}

void GeometryPool::create_buffers(uint64_t units, GLuint* buffer, GLuint* uv_buffer) const {
  gl_.CreateBuffers(1, buffer);
  gl_.NamedBufferStorage(*buffer, GLsizeiptr(units * kUnitBytes), nullptr, GL_DYNAMIC_STORAGE_BIT);
  if (uvs_) {
    gl_.CreateBuffers(1, uv_buffer);
    gl_.NamedBufferStorage(*uv_buffer, GLsizeiptr(units * 8), nullptr, GL_DYNAMIC_STORAGE_BIT);
  }
}

bool GeometryPool::grow(uint64_t units) {
  if (capacity_ >= max_units_) return false;
  const uint64_t grown = std::min(max_units_, std::max(2 * capacity_, capacity_ + units));
  GLuint buffer = 0, uv_buffer = 0;
  create_buffers(grown, &buffer, &uv_buffer);
  gl_.CopyNamedBufferSubData(buffer_, buffer, 0, 0, GLsizeiptr(capacity_ * kUnitBytes));
  if (uvs_) gl_.CopyNamedBufferSubData(uv_buffer_, uv_buffer, 0, 0, GLsizeiptr(capacity_ * 8));
  for (GLuint b : {buffer_, uv_buffer_})  // draws already submitted keep reading the old one
    if (b) gl_.DeleteBuffers(1, &b);
  buffer_ = buffer, uv_buffer_ = uv_buffer;
  release(capacity_, grown - capacity_);
  capacity_ = grown;
  ++generation_;
  return true;
}

GeometryPool::~GeometryPool() {
  for (GLuint b : {buffer_, uv_buffer_})
    if (b) gl_.DeleteBuffers(1, &b);
}

void GeometryPool::begin_window() { ++window_; }

bool GeometryPool::acquire(uint32_t p) {
  if (at_[p] != kNone) {
    window_of_[p] = window_;
    touch(p);
    return true;
  }
  const uint64_t units = units_of(p);
  if (units > max_units_)
    throw std::runtime_error("--geometry-budget: a piece of " + std::to_string(units * unit_bytes() >> 10) +
                             " KiB does not fit in the budget's " + std::to_string(budget_bytes() >> 20) +
                             " MiB; give a larger budget");
  uint64_t start = 0;
  while (!allocate(units, &start)) {
    if (grow(units)) continue;
    if (tail_ == kNone || window_of_[tail_] == window_) return false;  // only this window's pieces left
    evict(tail_);
  }
  window_of_[p] = window_;
  const double t0 = now_ms();
  place(p, start);
  stats_.upload_ms += now_ms() - t0;
  ++stats_.uploads;
  return true;
}

void GeometryPool::preload() {
  begin_window();
  if (capacity_ < max_units_) grow(max_units_ - capacity_);  // at once, not doubling
  for (uint32_t p = 0; p < sizes_.size(); ++p) {
    uint64_t start = 0;
    if (at_[p] != kNone) continue;
    while (!allocate(units_of(p), &start))
      if (!grow(units_of(p))) return;
    place(p, start);
  }
}

void GeometryPool::place(uint32_t p, uint64_t start) {
  at_[p] = uint32_t(start);
  used_ += units_of(p);
  touch(p);
  upload(p);
}

void GeometryPool::upload(uint32_t p) {
  staging_.clear();
  staging_uvs_.clear();
  loader_(p, staging_, uv_buffer_ ? &staging_uvs_ : nullptr);
  const PieceSize& s = sizes_[p];
  if (staging_.size() != s.vertices * kUnitBytes + s.indices * 4 || (uv_buffer_ && staging_uvs_.size() != s.vertices))
    throw std::logic_error("GeometryPool: piece " + std::to_string(p) + " loaded with another size");
  gl_.NamedBufferSubData(buffer_, GLintptr(uint64_t(at_[p]) * kUnitBytes), GLsizeiptr(staging_.size()),
                         staging_.data());
  if (uv_buffer_ && s.vertices)
    gl_.NamedBufferSubData(uv_buffer_, GLintptr(uint64_t(at_[p]) * 8), GLsizeiptr(s.vertices * 8),
                           staging_uvs_.data());
  stats_.upload_bytes += staging_.size() + staging_uvs_.size() * 8;
}

bool GeometryPool::allocate(uint64_t units, uint64_t* start) {
  if (units == 0) {  // an empty piece: anywhere (nothing is read there)
    *start = 0;
    return true;
  }
  auto it = free_by_size_.lower_bound(units);
  if (it == free_by_size_.end()) return false;
  const uint64_t len = it->first, at = it->second;
  free_by_size_.erase(it);
  free_by_start_.erase(at);
  if (len > units) {
    free_by_start_[at + units] = len - units;
    free_by_size_.emplace(len - units, at + units);
  }
  *start = at;
  return true;
}

void GeometryPool::release(uint64_t start, uint64_t units) {
  if (units == 0) return;
  auto erase_size = [&](uint64_t len, uint64_t at) {
    for (auto [b, e] = free_by_size_.equal_range(len); b != e; ++b)
      if (b->second == at) {
        free_by_size_.erase(b);
        return;
      }
  };
  auto next = free_by_start_.lower_bound(start);
  if (next != free_by_start_.end() && next->first == start + units) {  // merge with the range after
    units += next->second;
    erase_size(next->second, next->first);
    next = free_by_start_.erase(next);
  }
  if (next != free_by_start_.begin()) {  // merge with the range before
    auto prev = std::prev(next);
    if (prev->first + prev->second == start) {
      start = prev->first;
      units += prev->second;
      erase_size(prev->second, prev->first);
      free_by_start_.erase(prev);
    }
  }
  free_by_start_[start] = units;
  free_by_size_.emplace(units, start);
}

void GeometryPool::evict(uint32_t p) {
  unlink(p);
  const uint64_t units = units_of(p);
  release(at_[p], units);
  used_ -= units;
  at_[p] = kNone;
  ++stats_.evictions;
}

void GeometryPool::unlink(uint32_t p) {
  if (prev_[p] != kNone) next_[prev_[p]] = next_[p];
  else if (head_ == p) head_ = next_[p];
  if (next_[p] != kNone) prev_[next_[p]] = prev_[p];
  else if (tail_ == p) tail_ = prev_[p];
  prev_[p] = next_[p] = kNone;
}

void GeometryPool::touch(uint32_t p) {
  if (head_ == p) return;
  unlink(p);
  next_[p] = head_;
  if (head_ != kNone) prev_[head_] = p;
  head_ = p;
  if (tail_ == kNone) tail_ = p;
}

void print_geometry_line(std::FILE* out, const std::string& who, const GeometryPool* pool) {
  if (!pool) return;
  const GeometryPool::Stats& s = pool->stats();
  std::fprintf(out, "%s: geometry: budget_mb=%.0f arena_mb=%.0f scene_geometry_mb=%.0f pieces=%zu uploads=%llu upload_mb=%.1f "
              "upload_ms=%.0f evictions=%llu cut_calls=%llu\n",
              who.c_str(), pool->budget_bytes() / 1e6, pool->capacity_bytes() / 1e6, pool->total_bytes() / 1e6,
              pool->pieces(),
              static_cast<unsigned long long>(s.uploads), s.upload_bytes / 1e6, s.upload_ms,
              static_cast<unsigned long long>(s.evictions), static_cast<unsigned long long>(s.extra_windows));
  std::fflush(out);
}

}  // namespace occ

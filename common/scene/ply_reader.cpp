// The PLY reader (ply_reader.hpp): the header, then the body read from the mapped file row by
// row, every read checked against the bytes left.
#include "common/scene/ply_reader.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string_view>

#include "common/error.hpp"
#include "common/mapped_file.hpp"
#include "common/scene/model_mesh.hpp"

namespace occ {
namespace {

enum class Type : uint8_t { I8, U8, I16, U16, I32, U32, F32, F64 };
enum class Format : uint8_t { Ascii, Little, Big };

size_t type_size(Type t) {
  static constexpr size_t kSize[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return kSize[size_t(t)];
}
bool is_integer(Type t) { return t != Type::F32 && t != Type::F64; }

std::optional<Type> parse_type(std::string_view s) {
  static constexpr std::pair<const char*, Type> kNames[] = {
      {"char", Type::I8},    {"int8", Type::I8},     {"uchar", Type::U8},  {"uint8", Type::U8},
      {"short", Type::I16},  {"int16", Type::I16},   {"ushort", Type::U16}, {"uint16", Type::U16},
      {"int", Type::I32},    {"int32", Type::I32},   {"uint", Type::U32},  {"uint32", Type::U32},
      {"float", Type::F32},  {"float32", Type::F32}, {"double", Type::F64}, {"float64", Type::F64}};
  for (const auto& [name, t] : kNames)
    if (s == name) return t;
  return std::nullopt;
}

struct Property {
  std::string name;
  Type type = Type::F32;
  bool list = false;
  Type count_type = Type::U8;  // lists only
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> props;
};

struct Header {
  Format format = Format::Ascii;
  std::vector<Element> elements;
  size_t body = 0;  // offset of the first byte after end_header's line
};

std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> w;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t b = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > b) w.push_back(line.substr(b, i - b));
  }
  return w;
}

Header parse_header(const std::string& file, const uint8_t* data, size_t size) {
  Header h;
  size_t at = 0, line_no = 0;
  auto fail = [&](const std::string& what) -> void {
    throw InputError(file + ": header line " + std::to_string(line_no) + ": " + what);
  };
  bool format_seen = false;
  for (;;) {
    ++line_no;
    const void* nl = at < size ? std::memchr(data + at, '\n', size - at) : nullptr;  // data: null when empty
    if (!nl) fail("the file ends inside the header (no end_header line): truncated or not PLY");
    const size_t end = size_t(static_cast<const uint8_t*>(nl) - data);
    const std::string_view line(reinterpret_cast<const char*>(data + at), end - at);
    at = end + 1;
    const std::vector<std::string_view> w = words(line);
    if (line_no == 1) {
      if (w.size() != 1 || w[0] != "ply") fail("not a PLY file (it must start with the line 'ply')");
      continue;
    }
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") break;
    if (w[0] == "format") {
      if (w.size() != 3 || w[2] != "1.0") fail("expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      if (w[1] == "ascii") h.format = Format::Ascii;
      else if (w[1] == "binary_little_endian") h.format = Format::Little;
      else if (w[1] == "binary_big_endian") h.format = Format::Big;
      else fail("unknown format '" + std::string(w[1]) + "'");
      format_seen = true;
    } else if (w[0] == "element") {
      Element e;
      if (w.size() != 3) fail("expected 'element NAME COUNT'");
      e.name = w[1];
      const auto [p, ec] = std::from_chars(w[2].data(), w[2].data() + w[2].size(), e.count);
      if (ec != std::errc() || p != w[2].data() + w[2].size()) fail("bad element count '" + std::string(w[2]) + "'");
      h.elements.push_back(std::move(e));
    } else if (w[0] == "property") {
      if (h.elements.empty()) fail("a property before any element");
      Property p;
      const bool list = w.size() == 5 && w[1] == "list";
      if (!list && w.size() != 3) fail("expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME'");
      const auto t = parse_type(w[list ? 3 : 1]);
      const auto ct = list ? parse_type(w[2]) : std::optional<Type>(Type::U8);
      if (!t || !ct) fail("unknown property type in '" + std::string(line) + "'");
      if (list && !is_integer(*ct)) fail("a list's count type must be an integer type");
      p = Property{std::string(w.back()), *t, list, *ct};
      h.elements.back().props.push_back(std::move(p));
    } else {
      fail("unknown header keyword '" + std::string(w[0]) + "'");
    }
  }
  if (!format_seen) throw InputError(file + ": header: no format line");
  h.body = at;
  return h;
}

template <class T>
T load(const uint8_t* p, bool swap) {
  T v;
  std::memcpy(&v, p, sizeof v);
  if (swap) {
    uint8_t b[sizeof v];
    std::memcpy(b, &v, sizeof v);
    std::reverse(b, b + sizeof v);
    std::memcpy(&v, b, sizeof v);
  }
  return v;
}

// The body's values in order, as doubles, from the ASCII or binary encoding. Every read checks
// the bytes left; a failed read throws through fail().
class Body {
 public:
  Body(const std::string& file, MappedFile& f, const Header& h)
      : file_(file), f_(f), at_(h.body), format_(h.format), swap_((h.format == Format::Big) == (std::endian::native == std::endian::little)) {}

  // The place named in errors: element and row.
  void place(const std::string& element, uint64_t row, uint64_t rows) {
    element_ = &element;
    row_ = row;
    rows_ = rows;
    if ((row & 0xffff) == 0) f_.drop_before(at_);
  }

  double value(Type t) {
    if (format_ == Format::Ascii) return ascii(t);
    const size_t n = type_size(t);
    if (f_.size() - at_ < n) fail("truncated (the file ends inside this row)");
    const uint8_t* p = f_.data() + at_;
    at_ += n;
    switch (t) {
      case Type::I8: return double(int8_t(*p));
      case Type::U8: return double(*p);
      case Type::I16: return double(load<int16_t>(p, swap_));
      case Type::U16: return double(load<uint16_t>(p, swap_));
      case Type::I32: return double(load<int32_t>(p, swap_));
      case Type::U32: return double(load<uint32_t>(p, swap_));
      case Type::F32: return double(load<float>(p, swap_));
      case Type::F64: return load<double>(p, swap_);
    }
    return 0;
  }

  // What follows the last element: only whitespace is accepted (ASCII writers end with a newline;
  // binary files have nothing).
  void expect_end() {
    for (size_t i = at_; i < f_.size(); ++i) {
      const uint8_t c = f_.data()[i];
      if (c != ' ' && c != '\n' && c != '\r' && c != '\t')
        throw InputError(file_ + ": " + std::to_string(f_.size() - at_) + " bytes after the last element (at byte " +
                         std::to_string(at_) + "): the header's counts do not match the data");
    }
    f_.drop_before(f_.size(), 0);
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(file_ + ": element '" + *element_ + "' row " + std::to_string(row_) + " of " +
                     std::to_string(rows_) + " (byte " + std::to_string(at_) + "): " + what);
  }

 private:
  double ascii(Type t) {
    const char* p = reinterpret_cast<const char*>(f_.data());
    size_t i = at_;
    const size_t n = f_.size();
    while (i < n && (p[i] == ' ' || p[i] == '\n' || p[i] == '\r' || p[i] == '\t')) ++i;
    size_t e = i;
    while (e < n && p[e] != ' ' && p[e] != '\n' && p[e] != '\r' && p[e] != '\t') ++e;
    if (e == i) fail("truncated (the file ends inside this row)");
    if (e == n) fail("truncated (the file ends inside a number: an ASCII PLY ends with a newline)");
    at_ = e;
    double v = 0;
    if (is_integer(t)) {
      int64_t k = 0;
      const auto [q, ec] = std::from_chars(p + i, p + e, k);
      if (ec != std::errc() || q != p + e) fail("'" + std::string(p + i, e - i) + "' is not an integer");
      v = double(k);
    } else {
      const auto [q, ec] = std::from_chars(p + i, p + e, v);
      if (ec != std::errc() || q != p + e) fail("'" + std::string(p + i, e - i) + "' is not a number");
    }
    return v;
  }

  const std::string& file_;
  MappedFile& f_;
  size_t at_;
  Format format_;
  bool swap_;
  const std::string* element_ = nullptr;
  uint64_t row_ = 0, rows_ = 0;
};

// What each vertex property feeds: -1 nothing, 0..2 position, 3..5 normal, 6..9 colour.
std::vector<int> vertex_roles(const std::string& file, const Element& e, bool* normals, bool* colours) {
  static constexpr const char* kNames[] = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha"};
  std::vector<int> role(e.props.size(), -1);
  int seen[10] = {};
  for (size_t k = 0; k < e.props.size(); ++k)
    for (int r = 0; r < 10; ++r)
      if (e.props[k].name == kNames[r]) {
        if (e.props[k].list) throw InputError(file + ": vertex property '" + kNames[r] + "' must not be a list");
        if (r >= 6 && !(e.props[k].type == Type::U8 || e.props[k].type == Type::U16 || !is_integer(e.props[k].type)))
          throw InputError(file + ": vertex property '" + kNames[r] + "' must be uchar, ushort, float or double");
        role[k] = r;
        ++seen[r];
      }
  for (int r = 0; r < 10; ++r)
    if (seen[r] > 1) throw InputError(file + ": vertex property '" + kNames[r] + "' appears twice");
  if (!seen[0] || !seen[1] || !seen[2]) throw InputError(file + ": the vertex element has no x, y and z properties");
  *normals = seen[3] && seen[4] && seen[5];
  *colours = seen[6] && seen[7] && seen[8];
  return role;
}

// A colour component as 0..255: integers scaled from their type's range, floats from 0..1.
uint32_t colour_byte(Body& b, Type t, double v) {
  const double unit = t == Type::U8 ? v / 255.0 : t == Type::U16 ? v / 65535.0 : v;
  if (!(unit >= 0.0 && unit <= 1.0)) b.fail("colour component " + std::to_string(v) + " out of range");
  return uint32_t(std::lround(unit * 255.0));
}

void read_vertices(Body& b, const Element& e, const std::vector<int>& role, bool normals, bool colours, Mesh& m) {
  m.positions.resize(e.count);
  if (normals) m.normals.resize(e.count);
  if (colours) m.colors.assign(e.count, 0xff000000u);
  for (uint64_t row = 0; row < e.count; ++row) {
    b.place(e.name, row, e.count);
    for (size_t k = 0; k < e.props.size(); ++k) {
      const Property& p = e.props[k];
      if (p.list) {
        const double n = b.value(p.count_type);
        if (n < 0) b.fail("negative list length");
        for (double i = 0; i < n; ++i) b.value(p.type);
        continue;
      }
      const double v = b.value(p.type);
      const int r = role[k];
      if (r < 0) continue;
      if (r < 6 && !std::isfinite(float(v))) b.fail(p.name + " is not a finite float");
      if (r < 3) m.positions[row][r] = float(v);
      else if (r < 6) { if (normals) m.normals[row][r - 3] = float(v); }
      else if (colours) {
        const int shift = 8 * (r - 6);
        m.colors[row] = (m.colors[row] & ~(0xffu << shift)) | (colour_byte(b, p.type, v) << shift);
      }
    }
  }
}

void read_faces(Body& b, const Element& e, uint64_t vertices, Mesh& m) {
  size_t list = e.props.size();
  for (size_t k = 0; k < e.props.size(); ++k)
    if (e.props[k].list && (e.props[k].name == "vertex_indices" || e.props[k].name == "vertex_index")) list = k;
  if (list == e.props.size()) b.fail("the face element has no list property vertex_indices (or vertex_index)");
  if (!is_integer(e.props[list].type)) b.fail("vertex_indices must be a list of integers");
  m.indices.reserve(e.count * 3);
  uint32_t poly[256];
  for (uint64_t row = 0; row < e.count; ++row) {
    b.place(e.name, row, e.count);
    for (size_t k = 0; k < e.props.size(); ++k) {
      const Property& p = e.props[k];
      if (!p.list) {
        b.value(p.type);
        continue;
      }
      const double n = b.value(p.count_type);
      if (k == list && (n < 3 || n > 255)) b.fail("a face of " + std::to_string(int64_t(n)) + " vertices (3..255)");
      if (n < 0) b.fail("negative list length");
      for (uint32_t i = 0; double(i) < n; ++i) {
        const double v = b.value(p.type);
        if (k != list) continue;
        if (!(v >= 0 && v < double(vertices)))
          b.fail("vertex index " + std::to_string(int64_t(v)) + " out of range (" + std::to_string(vertices) +
                 " vertices)");
        poly[i] = uint32_t(v);
      }
      if (k != list) continue;
      for (uint32_t i = 1; i + 1 < uint32_t(n); ++i) m.indices.insert(m.indices.end(), {poly[0], poly[i], poly[i + 1]});
    }
  }
}

void skip_rows(Body& b, const Element& e) {
  for (uint64_t row = 0; row < e.count; ++row) {
    b.place(e.name, row, e.count);
    for (const Property& p : e.props) {
      const double n = p.list ? b.value(p.count_type) : 1.0;
      if (n < 0) b.fail("negative list length");
      for (double i = 0; i < n; ++i) b.value(p.type);
    }
  }
}

}  // namespace

Scene load_ply(const std::string& path) {
  MappedFile f;
  std::string why;
  if (!f.open(path, &why)) throw InputError(path + ": cannot read: " + why);
  Scene s;
  if (auto sf = source_file(path)) s.files.push_back(*sf);
  const Header h = parse_header(path, f.data(), f.size());
  Mesh m;
  m.name = std::filesystem::path(path).stem().string();
  bool normals = false, colours = false, vertex_seen = false, face_seen = false;
  uint64_t vertices = 0;
  Body body(path, f, h);
  for (const Element& e : h.elements) {
    if (e.name == "vertex" && !vertex_seen) {
      if (face_seen) throw InputError(path + ": the face element comes before the vertex element");
      if (e.count > UINT32_MAX) throw InputError(path + ": more than 2^32 vertices");
      const std::vector<int> role = vertex_roles(path, e, &normals, &colours);
      // A file too short for its rows fails at the first row past its end; a count far beyond the
      // file's size is refused before any allocation.
      if (h.format != Format::Ascii && e.count > f.size())
        throw InputError(path + ": " + std::to_string(e.count) + " vertices cannot fit in " + std::to_string(f.size()) +
                         " bytes (truncated or corrupt header)");
      read_vertices(body, e, role, normals, colours, m);
      vertices = e.count;
      vertex_seen = true;
    } else if (e.name == "face" && !face_seen) {
      if (!vertex_seen) throw InputError(path + ": the face element comes before the vertex element");
      if (e.count > f.size()) throw InputError(path + ": " + std::to_string(e.count) + " faces cannot fit in " +
                                               std::to_string(f.size()) + " bytes (truncated or corrupt header)");
      read_faces(body, e, vertices, m);
      face_seen = true;
    } else {
      if (h.format != Format::Ascii && e.count > f.size() && !e.props.empty())
        throw InputError(path + ": element '" + e.name + "': " + std::to_string(e.count) + " rows cannot fit in the file");
      skip_rows(body, e);
    }
  }
  body.expect_end();
  if (!vertex_seen) throw InputError(path + ": no vertex element");
  if (m.indices.empty()) throw InputError(path + ": no faces to draw (point clouds are not supported)");
  m.material = colours ? vertex_colour_material(s) : kNoMaterial;
  const ModelMeshCounts dropped = add_model_mesh(s, std::move(m), normals);
  if (dropped.meshes.empty()) throw InputError(path + ": no faces to draw (every face has zero area)");
  for (uint32_t k : dropped.meshes) s.objects.push_back(Object{k, glm::dmat4(1.0), s.meshes[k].name});
  s.zero_area_triangles = dropped.zero_area;
  s.repeated_triangles = dropped.repeated;
  s.source = path;
  return s;
}

bool is_ply_path(const std::string& path) { return has_extension_ci(path, ".ply"); }

}  // namespace occ

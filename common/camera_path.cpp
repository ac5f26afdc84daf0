#include "common/camera_path.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "common/cli.hpp"
#include "common/error.hpp"

namespace occ {

namespace {

constexpr double kFovyDeg = 60.0;

int parse_count(const std::string& spec, const std::string& text) {
  size_t used = 0;
  long n = -1;
  try {
    n = std::stol(text, &used);
  } catch (...) {
  }
  if (used != text.size() || n < 1 || n > 1000000)
    throw InputError("--path '" + spec + "': frame count must be 1..1000000, got '" + text + "'");
  return int(n);
}

Camera make(const glm::dvec3& eye, const glm::dvec3& target, const Aabb& b, const Viewport& vp) {
  Camera c = Camera::look_at(eye, target, {0, 1, 0}, kFovyDeg, double(vp.width) / vp.height, 0.1, 1.0);
  auto_near_far(c, b);
  return c;
}

std::vector<Camera> generated(const std::string& spec, const std::string& kind, int n,
                              const Aabb& b, const Viewport& vp) {
  if (b.empty()) throw InputError("--path '" + spec + "': the scene is empty, nothing to look at");
  const glm::dvec3 c = b.center(), e = b.extent();
  const double diag = glm::length(e);
  std::vector<Camera> path;
  for (int i = 0; i < n; ++i) {
    const double t = n > 1 ? double(i) / (n - 1) : 0.0;
    if (kind == "orbit") {
      double a = 2.0 * glm::pi<double>() * i / n;
      glm::dvec3 eye = c + glm::dvec3(std::cos(a) * 0.9 * diag, 0.35 * diag, std::sin(a) * 0.9 * diag);
      path.push_back(make(eye, c, b, vp));
    } else if (kind == "walk") {
      // Along the longer horizontal axis at eye height, swaying gently left and right.
      const bool along_x = e.x >= e.z;
      const double len = along_x ? e.x : e.z, side = along_x ? e.z : e.x;
      const double eye_y = b.min.y + std::min(1.7, 0.25 * e.y);
      const double s = -0.4 * len + 0.8 * len * t;
      const double sway = 0.002 * side * std::sin(6.0 * t);  // stays within a street of the city
      glm::dvec3 eye = along_x ? glm::dvec3(c.x + s, eye_y, c.z + sway) : glm::dvec3(c.x + sway, eye_y, c.z + s);
      const double yaw = 0.35 * std::sin(4.0 * t);
      glm::dvec3 fwd = along_x ? glm::dvec3(std::cos(yaw), 0, std::sin(yaw)) : glm::dvec3(std::sin(yaw), 0, std::cos(yaw));
      path.push_back(make(eye, eye + fwd, b, vp));
    } else {  // fly
      const double h = b.max.y + 0.15 * diag * (1.0 - 0.5 * t);
      glm::dvec3 eye(c.x - 0.6 * e.x + 1.2 * e.x * t, h, c.z - 0.5 * e.z + 0.6 * e.z * t);
      glm::dvec3 target = eye + glm::dvec3(0.5 * diag, -0.35 * diag, 0.25 * diag);
      path.push_back(make(eye, target, b, vp));
    }
  }
  return path;
}

// A cell: a finite number, white space allowed around it.
double parse_field(const std::string& file, int line, const char* column, const std::string& text) {
  size_t end = text.size();
  while (end > 0 && std::isspace(static_cast<unsigned char>(text[end - 1]))) --end;
  const std::optional<double> v = parse_finite(text.substr(0, end));
  if (!v)
    throw InputError(file + ": line " + std::to_string(line) + ": column " + column + ": '" +
                     text + "' is not a finite number");
  return *v;
}

std::vector<Camera> from_csv(const std::string& file, const Aabb& b, const Viewport& vp) {
  std::ifstream in(file);
  if (!in) throw InputError(file + ": cannot open camera path file");
  static const char* kColumns[] = {"frame", "eye_x", "eye_y", "eye_z", "target_x", "target_y", "target_z",
                                   "up_x", "up_y", "up_z", "fovy_deg", "near", "far"};
  std::vector<Camera> path;
  std::string row;
  for (int line = 1; std::getline(in, row); ++line) {
    if (!row.empty() && row.back() == '\r') row.pop_back();
    size_t first = row.find_first_not_of(" \t");
    if (first == std::string::npos || row[first] == '#') continue;
    if (path.empty() && row.compare(first, 5, "frame") == 0) continue;  // header
    std::vector<std::string> f;
    std::stringstream ss(row);
    for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
    const size_t max_columns = 13 + 4 * Sections::kMax;
    if (f.size() != 11 && (f.size() < 13 || f.size() > max_columns || (f.size() - 13) % 4 != 0))
      throw InputError(file + ": line " + std::to_string(line) + ": expected 11 or 13 columns, got " +
                       std::to_string(f.size()) + " (or 13 and 4 a section plane, at most " +
                       std::to_string(Sections::kMax) + ")");
    double v[13 + 4 * Sections::kMax];
    static const char* kPlane[] = {"section_a", "section_b", "section_c", "section_d"};
    for (size_t i = 0; i < f.size(); ++i) v[i] = parse_field(file, line, i < 13 ? kColumns[i] : kPlane[(i - 13) % 4], f[i]);
    auto where = file + ": line " + std::to_string(line) + ": ";
    if (v[0] != double(path.size()))
      throw InputError(where + "frame " + f[0] + " out of order (expected " + std::to_string(path.size()) + ")");
    glm::dvec3 eye(v[1], v[2], v[3]), target(v[4], v[5], v[6]), up(v[7], v[8], v[9]);
    if (!(glm::length(target - eye) > 0)) throw InputError(where + "eye equals target");
    if (!(glm::length(glm::cross(target - eye, up)) > 0))
      throw InputError(where + "up is zero or parallel to the view direction");
    if (!(v[10] > 0 && v[10] < 180)) throw InputError(where + "fovy_deg must be in (0, 180)");
    Camera c = Camera::look_at(eye, target, up, v[10], double(vp.width) / vp.height, 0.1, 1.0);
    if (f.size() >= 13) {
      c.near_dist = v[11];
      c.far_dist = v[12];
      for (size_t k = 13; k < f.size(); k += 4)
        c.sections.add({v[k], v[k + 1], v[k + 2], v[k + 3]}, where + "section " + std::to_string((k - 13) / 4));
    } else {
      auto_near_far(c, b);
    }
    if (auto why = c.invalid_reason()) throw InputError(where + *why);
    path.push_back(c);
  }
  if (path.empty()) throw InputError(file + ": no camera rows");
  return path;
}

}  // namespace

void auto_near_far(Camera& cam, const Aabb& b) {
  double far2 = 0;
  for (int i = 0; i < 8; ++i) {
    glm::dvec3 corner{(i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y, (i & 4) ? b.max.z : b.min.z};
    far2 = std::max(far2, glm::dot(corner - cam.eye, corner - cam.eye));
  }
  const double diag = std::max(b.diagonal(), 1e-9);
  cam.far_dist = std::max(std::sqrt(far2) * 1.01, diag * 1e-3);
  cam.near_dist = std::min(cam.far_dist * 1e-5, diag * 1e-2);
}

std::vector<Camera> load_camera_path(const std::string& spec, const Aabb& bounds, const Viewport& vp) {
  if (vp.width <= 0 || vp.height <= 0) throw InputError("camera path: viewport must be positive");
  size_t colon = spec.find(':');
  if (colon != std::string::npos) {
    std::string kind = spec.substr(0, colon);
    if (kind == "orbit" || kind == "walk" || kind == "fly")
      return generated(spec, kind, parse_count(spec, spec.substr(colon + 1)), bounds, vp);
    if (!std::ifstream(spec))
      throw InputError("--path '" + spec + "': unknown kind '" + kind + "' (expected orbit:N, walk:N, fly:N or a CSV file)");
  }
  if ((spec == "orbit" || spec == "walk" || spec == "fly") && !std::ifstream(spec))
    throw InputError("--path '" + spec + "': give a frame count, e.g. " + spec + ":60");
  return from_csv(spec, bounds, vp);
}

std::string camera_csv_fields(const Camera& c) {
  std::ostringstream out;
  out << std::setprecision(17);
  const glm::dvec3 t = c.eye + c.forward(), u = c.up();
  out << c.eye.x << ',' << c.eye.y << ',' << c.eye.z << ',' << t.x << ',' << t.y << ',' << t.z << ',' << u.x << ','
      << u.y << ',' << u.z << ',' << glm::degrees(c.fovy_rad) << ',' << c.near_dist << ',' << c.far_dist;
  for (int k = 0; k < c.sections.count; ++k) {
    const Plane& p = c.sections.planes[size_t(k)];
    out << ',' << p.n.x << ',' << p.n.y << ',' << p.n.z << ',' << p.d;
  }
  return out.str();
}

void save_camera_path(const std::string& file, const std::vector<Camera>& path) {
  std::ofstream out(file);
  if (!out) throw InputError(file + ": cannot write camera path");
  int planes = 0;
  for (const Camera& c : path) planes = std::max(planes, int(c.sections.count));
  out << "frame,eye_x,eye_y,eye_z,target_x,target_y,target_z,up_x,up_y,up_z,fovy_deg,near,far";
  for (int k = 0; k < planes; ++k) out << ",section" << k << "_a,section" << k << "_b,section" << k << "_c,section" << k << "_d";
  out << '\n';
  for (size_t i = 0; i < path.size(); ++i) out << i << ',' << camera_csv_fields(path[i]) << '\n';
  if (!out) throw InputError(file + ": write failed");
}

}  // namespace occ

// Camera paths: a CSV file or a path generated from the scene bounds.
//   CSV: frame,eye_x,eye_y,eye_z,target_x,target_y,target_z,up_x,up_y,up_z,fovy_deg[,near,far[,A,B,C,D...]]
//        optional header line starting with "frame"; '#' comment lines; frames 0,1,2,... in order;
//        after near and far, up to six section planes of that camera, four columns each
//        (section.hpp: keeps A*x + B*y + C*z + D >= 0), so that a path can move a cut.
//   orbit:N  circle around the scene, looking at its centre
//   walk:N   a walk through the scene at eye height along its longest horizontal axis (the hard
//            case for occlusion: walls and buildings right in front of the eye)
//   fly:N    a low fly-over looking forward and down
// Y is up. Near/far not given in the file are derived from the scene bounds (see auto_near_far).
#pragma once
#include <string>
#include <vector>

#include "common/camera.hpp"

namespace occ {

// Throws InputError naming the file/line/column or the spec.
std::vector<Camera> load_camera_path(const std::string& spec, const Aabb& scene_bounds,
                                     const Viewport& viewport);

// Near and far for a camera at `eye` that must see all of `bounds`: far reaches the farthest
// corner (+1%), near = far * 1e-5 but at most 1e-2 of the scene diagonal.
void auto_near_far(Camera& cam, const Aabb& bounds);

// Writes a path as CSV (with header and near/far columns) so a generated path can be replayed.
void save_camera_path(const std::string& file, const std::vector<Camera>& path);
// One camera as save_camera_path writes its row, without the frame number:
// "eye_x,...,fovy_deg,near,far[,A,B,C,D...]" (17 significant digits: a path of it replays the camera, eye,
// fov, near and far exactly, its orientation to a few units in the last place of a double).
std::string camera_csv_fields(const Camera& c);

}  // namespace occ

// Exact ray casting of the box world. Each pixel's ray d_w = R_w_c (x_n, y_n, 1) has unit
// camera-frame z, so the ray parameter of a hit is its depth z directly. Boxes are culled per
// frame: each box's clipped projection gives an image rectangle, and every 16 x 16 tile keeps
// the boxes overlapping it sorted by their nearest camera z, so a pixel stops testing as soon
// as no remaining box can be closer than its current hit.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "world.h"

namespace rgbdslam::synthetic {
namespace {

constexpr double kNearZ = 0.01;  // hits closer than this camera z are ignored [m]
constexpr int kTile = 16;        // culling tile size [px]
constexpr float kTinyDirection = 1e-9f;

struct CulledBox {
  float rlo[3], rhi[3];  // box corners minus the camera centre, world axes [m]
  float min_z;           // smallest camera-frame z over the box [m]: no hit is closer
  int box;               // index into World::boxes
};

struct Rect {
  int u0, v0, u1, v1;  // pixels [u0, u1) x [v0, v1)
};

// Image rectangle of the part of a box in front of z = kNearZ (corners in the camera frame).
bool projectedRect(const std::array<Vec3, 8>& p_c, const PinholeCamera& cam, Rect* rect) {
  double u_min = std::numeric_limits<double>::max(), v_min = u_min;
  double u_max = -u_min, v_max = -u_min;
  bool any = false;
  auto extend = [&](const Vec3& p) {
    const double u = cam.fx * p.x() / p.z() + cam.cx, v = cam.fy * p.y() / p.z() + cam.cy;
    u_min = std::min(u_min, u), u_max = std::max(u_max, u);
    v_min = std::min(v_min, v), v_max = std::max(v_max, v);
    any = true;
  };
  for (int k = 0; k < 8; ++k) {
    if (p_c[k].z() >= kNearZ) extend(p_c[k]);
    for (const int bit : {1, 2, 4}) {  // the edge from k to k | bit, once
      if (k & bit) continue;
      const Vec3& a = p_c[k];
      const Vec3& b = p_c[k | bit];
      if ((a.z() < kNearZ) == (b.z() < kNearZ)) continue;
      extend(a + (kNearZ - a.z()) / (b.z() - a.z()) * (b - a));  // crossing of z = kNearZ
    }
  }
  if (!any) return false;
  const double big = 4.0 * (cam.width + cam.height);  // keeps the casts in range
  rect->u0 = std::max(0, static_cast<int>(std::floor(std::max(u_min, -big))) - 1);
  rect->v0 = std::max(0, static_cast<int>(std::floor(std::max(v_min, -big))) - 1);
  rect->u1 = std::min(cam.width, static_cast<int>(std::ceil(std::min(u_max, big))) + 2);
  rect->v1 = std::min(cam.height, static_cast<int>(std::ceil(std::min(v_max, big))) + 2);
  return rect->u0 < rect->u1 && rect->v0 < rect->v1;
}

// Per-frame culling: the boxes in view sorted by min_z, and per tile the indices (into that
// list, so ascending = nearest first) of the boxes whose rectangle overlaps the tile.
struct TileLists {
  std::vector<CulledBox> boxes;
  int tiles_x = 0, tiles_y = 0;
  std::vector<int> offsets;  // tile t's list is indices[offsets[t], offsets[t + 1])
  std::vector<int> indices;
};

TileLists cullBoxes(const World& world, const PinholeCamera& cam, const SE3& T_w_c) {
  const Mat3 R_c_w = T_w_c.rotationMatrix().transpose();
  const Vec3& o = T_w_c.translation();
  TileLists lists;
  std::vector<Rect> rects;
  for (size_t i = 0; i < world.boxes.size(); ++i) {
    const Box& box = world.boxes[i];
    std::array<Vec3, 8> p_c;
    for (int k = 0; k < 8; ++k) {
      const Vec3 corner((k & 1) ? box.hi.x() : box.lo.x(), (k & 2) ? box.hi.y() : box.lo.y(),
                        (k & 4) ? box.hi.z() : box.lo.z());
      p_c[k] = R_c_w * (corner - o);
    }
    Rect rect;
    if (!projectedRect(p_c, cam, &rect)) continue;
    CulledBox culled;
    culled.min_z = std::numeric_limits<float>::max();
    for (const Vec3& p : p_c) culled.min_z = std::min(culled.min_z, static_cast<float>(p.z()));
    for (int a = 0; a < 3; ++a) {
      culled.rlo[a] = static_cast<float>(box.lo[a] - o[a]);
      culled.rhi[a] = static_cast<float>(box.hi[a] - o[a]);
    }
    culled.box = static_cast<int>(i);
    lists.boxes.push_back(culled);
    rects.push_back(rect);
  }
  std::vector<int> order(lists.boxes.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return lists.boxes[a].min_z < lists.boxes[b].min_z;
  });
  lists.tiles_x = (cam.width + kTile - 1) / kTile;
  lists.tiles_y = (cam.height + kTile - 1) / kTile;
  std::vector<std::vector<int>> per_tile(lists.tiles_x * lists.tiles_y);
  for (const int b : order) {
    const Rect& r = rects[b];
    for (int ty = r.v0 / kTile; ty <= (r.v1 - 1) / kTile; ++ty) {
      for (int tx = r.u0 / kTile; tx <= (r.u1 - 1) / kTile; ++tx) {
        per_tile[ty * lists.tiles_x + tx].push_back(b);
      }
    }
  }
  lists.offsets.push_back(0);
  for (const auto& tile : per_tile) {
    lists.indices.insert(lists.indices.end(), tile.begin(), tile.end());
    lists.offsets.push_back(static_cast<int>(lists.indices.size()));
  }
  return lists;
}

// floor(log2(texels per pixel)), clamped to the mip levels there are.
int mipLevel(float texels_per_pixel, int num_levels) {
  if (!(texels_per_pixel >= 2.f)) return 0;
  uint32_t bits;
  std::memcpy(&bits, &texels_per_pixel, sizeof(bits));
  const int exponent = static_cast<int>((bits >> 23) & 0xff) - 127;
  return std::min(exponent, num_levels - 1);
}

float sampleBilinear(const cv::Mat& level, float x, float y) {
  x = std::clamp(x, 0.f, level.cols - 1.001f);
  y = std::clamp(y, 0.f, level.rows - 1.001f);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const float fx = x - x0, fy = y - y0;
  const uint8_t* r0 = level.ptr<uint8_t>(y0) + x0;
  const uint8_t* r1 = r0 + level.step[0];
  const float top = r0[0] + fx * (r0[1] - r0[0]);
  const float bottom = r1[0] + fx * (r1[1] - r1[0]);
  return top + fy * (bottom - top);
}

// Everything about one ray's hit that the pixel needs.
struct RayHit {
  float z = 0;  // camera-frame depth [m]
  const CulledBox* box = nullptr;
};

inline RayHit castRay(const float inv[3], const CulledBox* boxes,
                      const int* candidates, int count) {
  RayHit hit;
  float best = std::numeric_limits<float>::max();
  for (int i = 0; i < count; ++i) {
    const CulledBox& b = boxes[candidates[i]];
    if (b.min_z >= best) break;  // sorted: nothing further can be closer
    float t0 = b.rlo[0] * inv[0], t1 = b.rhi[0] * inv[0];
    float t_near = std::min(t0, t1), t_far = std::max(t0, t1);
    t0 = b.rlo[1] * inv[1], t1 = b.rhi[1] * inv[1];
    t_near = std::max(t_near, std::min(t0, t1)), t_far = std::min(t_far, std::max(t0, t1));
    t0 = b.rlo[2] * inv[2], t1 = b.rhi[2] * inv[2];
    t_near = std::max(t_near, std::min(t0, t1)), t_far = std::min(t_far, std::max(t0, t1));
    if (t_near <= t_far && t_near > static_cast<float>(kNearZ) && t_near < best) {
      best = t_near;
      hit.box = &b;
    }
  }
  hit.z = hit.box ? best : 0.f;
  return hit;
}

// Where one pixel's results go.
struct PixelOut {
  uint8_t* bgr;
  float* depth;
  uint8_t* label;
  float* hit_z;
  float* cos_incidence;
};

// Colour (BGR) and label of a hit, writing depth only for surfaces that return it.
inline void shadeHit(const World& world, float fx, const float d[3], const float inv[3],
                     const RayHit& hit, const PixelOut& out) {
  const CulledBox& b = *hit.box;
  int axis = 0;
  float entry = -std::numeric_limits<float>::max();
  for (int a = 0; a < 3; ++a) {
    const float t = std::min(b.rlo[a] * inv[a], b.rhi[a] * inv[a]);
    if (t > entry) entry = t, axis = a;
  }
  const Box& box = world.boxes[b.box];
  const Face& face = box.faces[2 * axis + (d[axis] > 0 ? 0 : 1)];
  const Texture& texture = world.textures[face.texture];
  const int axis_u = axis == 0 ? 1 : 0, axis_v = axis == 2 ? 1 : 2;
  const float x = (hit.z * d[axis_u] - b.rlo[axis_u]) * texture.inv_texel;
  const float y = (hit.z * d[axis_v] - b.rlo[axis_v]) * texture.inv_texel;
  // Texels under one pixel: range / (f cos(incidence)) = z |d|^2 / (f |d_axis|).
  const float d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  const float footprint = hit.z * d2 / (fx * std::abs(d[axis])) * texture.inv_texel;
  const int level = mipLevel(footprint, static_cast<int>(texture.levels.size()));
  const float scale = 1.f / static_cast<float>(1 << level);
  const float albedo = sampleBilinear(texture.levels[level], x * scale, y * scale);
  for (int c = 0; c < 3; ++c) {
    out.bgr[c] = static_cast<uint8_t>(std::min(255.f, albedo * face.gain[c] + 0.5f));
  }
  const bool returns_depth =
      box.surface == SyntheticSurface::kDiffuse || box.surface == SyntheticSurface::kShiny;
  *out.depth = returns_depth ? hit.z : 0.f;
  *out.label = static_cast<uint8_t>(box.surface);
  *out.hit_z = hit.z;
  // The face's normal is the hit axis: cos(theta) = |d_axis| / |d|.
  *out.cos_incidence = std::abs(d[axis]) / std::sqrt(d2);
}

void renderTile(const World& world, const PinholeCamera& cam, const Mat3& R_w_c,
                const TileLists& lists, int tx, int ty, CleanFrame* out) {
  const int tile = ty * lists.tiles_x + tx;
  const int* candidates = lists.indices.data() + lists.offsets[tile];
  const int count = lists.offsets[tile + 1] - lists.offsets[tile];
  const Eigen::Matrix3f R = R_w_c.cast<float>();
  const float fx = static_cast<float>(cam.fx);
  const int u_end = std::min(cam.width, (tx + 1) * kTile);
  const int v_end = std::min(cam.height, (ty + 1) * kTile);
  for (int v = ty * kTile; v < v_end; ++v) {
    const float yn = static_cast<float>((v - cam.cy) / cam.fy);
    uint8_t* bgr = out->colour.ptr<uint8_t>(v);
    float* depth = out->depth_m.ptr<float>(v);
    uint8_t* label = out->surfaces.ptr<uint8_t>(v);
    float* hit_z = out->hit_z.ptr<float>(v);
    float* cos_incidence = out->cos_incidence.ptr<float>(v);
    for (int u = tx * kTile; u < u_end; ++u) {
      const float xn = static_cast<float>((u - cam.cx) / cam.fx);
      float d[3], inv[3];
      for (int a = 0; a < 3; ++a) {
        d[a] = R(a, 0) * xn + R(a, 1) * yn + R(a, 2);
        if (std::abs(d[a]) < kTinyDirection) d[a] = kTinyDirection;  // keeps 1/d finite
        inv[a] = 1.f / d[a];
      }
      const RayHit hit = castRay(inv, lists.boxes.data(), candidates, count);
      if (!hit.box) continue;  // stays black, no depth, kNothing
      shadeHit(world, fx, d, inv, hit,
               PixelOut{bgr + 3 * u, depth + u, label + u, hit_z + u, cos_incidence + u});
    }
  }
}

}  // namespace

void castRays(const World& world, const PinholeCamera& camera, const SE3& T_w_c,
              CleanFrame* out) {
  out->colour.create(camera.height, camera.width, CV_8UC3);
  out->depth_m.create(camera.height, camera.width, CV_32FC1);
  out->surfaces.create(camera.height, camera.width, CV_8UC1);
  out->colour.setTo(cv::Scalar::all(0));
  out->depth_m.setTo(cv::Scalar(0));
  out->surfaces.setTo(cv::Scalar(static_cast<int>(SyntheticSurface::kNothing)));
  out->hit_z.create(camera.height, camera.width, CV_32FC1);
  out->cos_incidence.create(camera.height, camera.width, CV_32FC1);
  out->hit_z.setTo(cv::Scalar(0));
  out->cos_incidence.setTo(cv::Scalar(0));
  const TileLists lists = cullBoxes(world, camera, T_w_c);
  const Mat3 R_w_c = T_w_c.rotationMatrix();
  for (int ty = 0; ty < lists.tiles_y; ++ty) {
    for (int tx = 0; tx < lists.tiles_x; ++tx) renderTile(world, camera, R_w_c, lists, tx, ty, out);
  }
}

}  // namespace rgbdslam::synthetic

// Rendering through a distorted lens: an ideal pinhole canvas, resampled per pixel.
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>

#include "world.h"

namespace rgbdslam::synthetic {
namespace {

constexpr double kRoundTripTolerancePx = 0.01;  // project(unproject(p)) must return to p [px]
constexpr int kCheckStepPx = 8;                 // grid spacing of checkLens [px]
constexpr double kMaxCanvasFactor = 4.0;        // canvas side at most this times the image's
constexpr int kCanvasMarginPx = 2;              // canvas border beyond the extreme rays [px]

// The canvas pixel (ideal pinhole, canvas principal point 0,0 shifted later) of pixel uv of
// the distorted camera, or nullopt when the distortion cannot be inverted there.
std::optional<Eigen::Vector2d> idealPixel(const PinholeCamera& camera, const Eigen::Vector2d& uv) {
  const Eigen::Vector2d m = camera.unprojectToPlane(uv);
  if (!m.allFinite() || (camera.distortAndScale(m) - uv).norm() > kRoundTripTolerancePx) {
    return std::nullopt;
  }
  return Eigen::Vector2d(camera.fx * m.x() + camera.cx, camera.fy * m.y() + camera.cy);
}

}  // namespace

Status checkLens(const PinholeCamera& camera) {
  double u_min = 0, u_max = 0, v_min = 0, v_max = 0;
  bool first = true;
  auto check = [&](int u, int v) -> Status {
    const auto p = idealPixel(camera, Eigen::Vector2d(u, v));
    if (!p) {
      return Error{"distortion cannot be inverted at pixel (" + std::to_string(u) + ", " +
                   std::to_string(v) + ")"};
    }
    u_min = first ? p->x() : std::min(u_min, p->x()), u_max = first ? p->x() : std::max(u_max, p->x());
    v_min = first ? p->y() : std::min(v_min, p->y()), v_max = first ? p->y() : std::max(v_max, p->y());
    first = false;
    return {};
  };
  for (int v = 0; v < camera.height; v += kCheckStepPx) {
    for (int u = 0; u < camera.width; u += kCheckStepPx) {
      if (Status s = check(u, v); !s) return s;
    }
  }
  for (int u = 0; u < camera.width; ++u) {
    if (Status s = check(u, 0); !s) return s;
    if (Status s = check(u, camera.height - 1); !s) return s;
  }
  for (int v = 0; v < camera.height; ++v) {
    if (Status s = check(0, v); !s) return s;
    if (Status s = check(camera.width - 1, v); !s) return s;
  }
  if (u_max - u_min > kMaxCanvasFactor * camera.width ||
      v_max - v_min > kMaxCanvasFactor * camera.height) {
    return Error{"distortion widens the view beyond 4x the image"};
  }
  return {};
}

LensResampling makeLensResampling(const PinholeCamera& camera) {
  LensResampling lens;
  cv::Mat ideal_u(camera.height, camera.width, CV_32FC1), ideal_v(camera.height, camera.width, CV_32FC1);
  double u_min = 0, u_max = 0, v_min = 0, v_max = 0;
  bool first = true;
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const auto p = idealPixel(camera, Eigen::Vector2d(u, v));
      // A pixel that cannot be inverted (checkLens samples a grid) stays black, no depth.
      const Eigen::Vector2d q = p ? *p : Eigen::Vector2d(-1e6, -1e6);
      ideal_u.at<float>(v, u) = static_cast<float>(q.x());
      ideal_v.at<float>(v, u) = static_cast<float>(q.y());
      if (!p) continue;
      u_min = first ? q.x() : std::min(u_min, q.x()), u_max = first ? q.x() : std::max(u_max, q.x());
      v_min = first ? q.y() : std::min(v_min, q.y()), v_max = first ? q.y() : std::max(v_max, q.y());
      first = false;
    }
  }
  const double u0 = std::floor(u_min) - kCanvasMarginPx, v0 = std::floor(v_min) - kCanvasMarginPx;
  lens.canvas = camera;
  lens.canvas.k1 = lens.canvas.k2 = lens.canvas.p1 = lens.canvas.p2 = lens.canvas.k3 = 0;
  lens.canvas.width = static_cast<int>(std::ceil(u_max) - u0) + kCanvasMarginPx + 1;
  lens.canvas.height = static_cast<int>(std::ceil(v_max) - v0) + kCanvasMarginPx + 1;
  lens.canvas.cx = camera.cx - u0;
  lens.canvas.cy = camera.cy - v0;
  lens.map_u = ideal_u - static_cast<float>(u0);
  lens.map_v = ideal_v - static_cast<float>(v0);
  return lens;
}

void resampleThroughLens(const LensResampling& lens, CleanFrame* frame) {
  CleanFrame out;
  cv::remap(frame->colour, out.colour, lens.map_u, lens.map_v, cv::INTER_LINEAR,
            cv::BORDER_CONSTANT, cv::Scalar::all(0));
  cv::remap(frame->depth_m, out.depth_m, lens.map_u, lens.map_v, cv::INTER_NEAREST,
            cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::remap(frame->surfaces, out.surfaces, lens.map_u, lens.map_v, cv::INTER_NEAREST,
            cv::BORDER_CONSTANT, cv::Scalar(static_cast<int>(SyntheticSurface::kNothing)));
  for (auto [in, to] : {std::pair{&frame->hit_z, &out.hit_z},
                        std::pair{&frame->cos_incidence, &out.cos_incidence}}) {
    cv::remap(*in, *to, lens.map_u, lens.map_v, cv::INTER_NEAREST, cv::BORDER_CONSTANT,
              cv::Scalar(0));
  }
  *frame = std::move(out);
}

}  // namespace rgbdslam::synthetic

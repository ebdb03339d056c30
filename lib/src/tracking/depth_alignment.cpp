#include "rgbdslam/tracking/depth_alignment.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace rgbdslam {
namespace {

constexpr int kFitSteps = 5;               // a plane fit reads a (2 kFitSteps + 1)^2 grid of pixels
constexpr int kMinFitRadiusPx = 4, kMaxFitRadiusPx = 48;  // ...spread over this radius [px]
constexpr double kMinFitFraction = 0.6;    // ...at least this fraction of them with a reading
constexpr double kMinSampleDepthM = 0.1;   // samples nearer the camera are skipped [m]

struct PlaneFit {
  Eigen::Vector3d centroid;
  Eigen::Vector3d normal;  // towards the camera
  double rms = 0.0;        // RMS distance of the readings from the plane [m]
  double normal_var = 0.0;  // variance of the normal's tilt [rad^2]
  int count = 0;
};

// Least-squares plane through the readings of a grid within 'radius' of (u, v).
bool fitPlane(const cv::Mat& depth_m, const PinholeCamera& camera, int u, int v, int radius,
              PlaneFit* fit) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  int count = 0, tried = 0;
  const int step = std::max(1, radius / kFitSteps);
  for (int dv = -radius; dv <= radius; dv += step) {
    const int y = v + dv;
    if (y < 0 || y >= depth_m.rows) continue;
    const float* row = depth_m.ptr<float>(y);
    for (int du = -radius; du <= radius; du += step) {
      const int x = u + du;
      if (x < 0 || x >= depth_m.cols) continue;
      ++tried;
      const float z = row[x];
      if (!(z > 0.f)) continue;  // NaN: no reading
      const Eigen::Vector3d p = camera.unproject(Eigen::Vector2d(x, y), z);
      sum += p;
      outer.noalias() += p * p.transpose();
      ++count;
    }
  }
  if (count < 4 || count < kMinFitFraction * tried) return false;
  fit->count = count;
  fit->centroid = sum / count;
  const Eigen::Matrix3d covariance = outer / count - fit->centroid * fit->centroid.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(covariance);
  if (eigen.info() != Eigen::Success) return false;
  fit->normal = eigen.eigenvectors().col(0);  // smallest eigenvalue first
  if (fit->normal.dot(fit->centroid) > 0.0) fit->normal = -fit->normal;
  fit->rms = std::sqrt(std::max(0.0, eigen.eigenvalues()(0)));
  // A plane fit's tilt error: the noise across the plane over the readings' spread along it
  // (the narrower direction, to be safe).
  fit->normal_var = std::max(0.0, eigen.eigenvalues()(0)) / (count * std::max(1e-12, eigen.eigenvalues()(1)));
  return fit->normal.allFinite();
}

}  // namespace

void DepthAlignmentOptions::bind(OptionRegistry* r, const std::string& s) {
  r->bind(s, "depth_align", &enabled,
          "where the points found are too few to fix the pose, align the frame's depth to the "
          "nearest keyframes' surfaces (point-to-plane) in the same fit (depth modes); such a "
          "frame is dodgy");
  r->bind(s, "depth_align_below_points", &below_points, 0, 100000, "points",
          "depth joins the pose fit when fewer points than this are found, or the points "
          "found do not fix the pose");
  r->bind(s, "depth_align_keyframes", &keyframes, 1, 16, "keyframes",
          "the nearest keyframes whose surface samples are aligned against");
  r->bind(s, "depth_align_grid_px", &grid_px, 4, 128, "px", "one surface sample per grid cell");
  r->bind(s, "depth_align_fit_radius_m", &fit_radius_m, 0.01, 1.0, "m",
          "a sample's plane is fitted to the readings within this radius (4-48 px in the image)");
  r->bind(s, "depth_align_max_plane_rms_sigmas", &max_plane_rms_sigmas, 0.1, 100.0, "sigmas",
          "a sample only where the readings lie on a plane within this many depth sigmas (RMS)");
  r->bind(s, "depth_align_max_incidence_deg", &max_incidence_deg, 0.0, 89.0, "deg",
          "samples seen more obliquely than this (ray against normal) are skipped");
  r->bind(s, "depth_align_effective_samples", &effective_samples, 1, 1000000, "samples",
          "the surface samples count as at most this many independent measurements in the "
          "pose's uncertainty (their systematic errors are shared)");
  r->bind(s, "depth_align_max_step_m", &max_step_m, 0.0, 10.0, "m",
          "the aligned pose must lie within this of the constant-velocity prediction");
  r->bind(s, "depth_align_max_step_deg", &max_step_deg, 0.0, 180.0, "deg", "...and within this angle");
  r->bind(s, "depth_align_min_inliers", &min_inliers, 3, 1000000, "samples",
          "fewer samples agreeing with the aligned pose: depth does not hold it");
  r->bind(s, "depth_align_min_inlier_ratio", &min_inlier_ratio, 0.0, 1.0, "",
          "...nor when fewer than this fraction of the samples with a reading agree");
  r->bind(s, "depth_align_reference_step_m", &reference_step_m, 0.0, 10.0, "m",
          "a depth-aided frame's surfaces become the reference for the next frames' "
          "alignment once the camera is this far from the last reference (0: no reference)");
  r->bind(s, "depth_align_reference_step_deg", &reference_step_deg, 0.0, 180.0, "deg",
          "...or turned this far from it");
}

std::vector<SurfaceSample> sampleSurface(const cv::Mat& depth_m, const PinholeCamera& camera,
                                         const NoiseModel& noise, const DepthAlignmentOptions& options) {
  std::vector<SurfaceSample> samples;
  if (depth_m.empty() || depth_m.type() != CV_32FC1 || options.grid_px < 1) return samples;
  const double min_cos = std::cos(options.max_incidence_deg * M_PI / 180.0);
  const int half = options.grid_px / 2;
  PlaneFit fit;
  for (int v = half; v < depth_m.rows; v += options.grid_px) {
    for (int u = half; u < depth_m.cols; u += options.grid_px) {
      const float z_centre = depth_m.at<float>(v, u);
      if (!(z_centre > 0.f)) continue;
      // A metric window: the readings' noise (a z^2) grows with distance, and a normal is
      // only as good as the plane's extent against that noise.
      const int radius = std::clamp(static_cast<int>(camera.fx * options.fit_radius_m / z_centre),
                                    kMinFitRadiusPx, kMaxFitRadiusPx);
      if (!fitPlane(depth_m, camera, u, v, radius, &fit)) continue;
      const double z = fit.centroid.z();
      if (z < kMinSampleDepthM) continue;
      const double cos_incidence = -fit.normal.dot(fit.centroid.normalized());
      if (cos_incidence < min_cos) continue;
      const double sigma = noise.sigmaDepth(z);
      if (fit.rms > options.max_plane_rms_sigmas * sigma) continue;  // an edge or clutter
      SurfaceSample sample;
      sample.p = fit.centroid.cast<float>();
      sample.n = fit.normal.cast<float>();
      // The centroid averages 'count' readings, whose noise is along the rays.
      sample.sigma = static_cast<float>(sigma * cos_incidence / std::sqrt(fit.count));
      sample.normal_var = static_cast<float>(fit.normal_var);
      samples.push_back(sample);
    }
  }
  return samples;
}

Eigen::Matrix<double, 6, 6> PointToPlaneResiduals::honestInformation(
    const Eigen::Matrix<double, 6, 6>& weighted, int effective_samples, int samples) const {
  const double share = samples > effective_samples ? static_cast<double>(effective_samples) / samples : 1.0;
  // The robust weights scale the normals' share as they scale the whole (on average).
  const double full = information_.trace();
  const double weight = full > 0.0 ? weighted.trace() / full : 0.0;
  return share * (weighted - weight * normal_noise_information_);
}

void appendAnchors(const std::vector<SurfaceSample>& samples, const SE3& T_w_k,
                   std::vector<SurfaceAnchor>* anchors) {
  const Mat3 R = T_w_k.rotationMatrix();
  for (const SurfaceSample& s : samples) {
    anchors->push_back({T_w_k * s.p.cast<double>(), R * s.n.cast<double>(), s.sigma, s.normal_var});
  }
}

PointToPlaneResiduals::PointToPlaneResiduals(const std::vector<SurfaceAnchor>& anchors,
                                             const RgbdFrame& frame, const PinholeCamera& camera,
                                             const NoiseModel& noise, double min_depth_m,
                                             double max_depth_m, double max_incidence_deg)
    : anchors_(anchors), frame_(frame), camera_(camera), noise_(noise),
      min_cos_incidence_(std::cos(max_incidence_deg * M_PI / 180.0)) {
  if (frame.depth_scale > 0) {
    raw_min_ = static_cast<uint16_t>(std::clamp(std::ceil(min_depth_m * frame.depth_scale), 1.0, 65535.0));
    raw_max_ = static_cast<uint16_t>(std::clamp(std::floor(max_depth_m * frame.depth_scale), 1.0, 65535.0));
  }
}

void PointToPlaneResiduals::linearise(const SE3& T_c_w, std::vector<double>* r,
                                      std::vector<Eigen::Matrix<double, 1, 6>>* J) const {
  r->clear();
  J->clear();
  normal_noise_information_.setZero();
  information_.setZero();
  const cv::Mat& depth = frame_.depth;
  if (depth.empty() || depth.type() != CV_16UC1 || !(frame_.depth_scale > 0)) return;
  const Mat3 R = T_c_w.rotationMatrix();
  for (const SurfaceAnchor& a : anchors_) {
    const Vec3 p_c = T_c_w * a.p_w;
    if (!(p_c.z() > kMinSampleDepthM)) continue;
    const Vec3 n_c = R * a.n_w;
    if (-n_c.dot(p_c.normalized()) < min_cos_incidence_) continue;  // oblique or facing away
    const auto uv = camera_.project(p_c);
    if (!uv) continue;
    const int u = static_cast<int>(std::lround(uv->x())), v = static_cast<int>(std::lround(uv->y()));
    if (u < 0 || v < 0 || u >= depth.cols || v >= depth.rows) continue;
    const uint16_t raw = depth.at<uint16_t>(v, u);
    if (raw < raw_min_ || raw > raw_max_) continue;
    const double z = raw / frame_.depth_scale;
    const Vec3 q_c = camera_.unproject(Eigen::Vector2d(u, v), z);
    // The reading's noise is along its ray: it moves q_c by dz q_c / z.
    const double sigma_reading = noise_.sigmaDepth(z) * std::abs(n_c.dot(q_c)) / z;
    const double inv_sigma = 1.0 / std::sqrt(sigma_reading * sigma_reading + a.sigma * a.sigma);
    if (!std::isfinite(inv_sigma)) continue;
    // r = n_c . (q_c - p_c); under T_c_w <- exp(xi) T_c_w, p_c moves by v + w x p_c and n_c
    // by w x n_c: dr/dv = -n_c, dr/dw = n_c x q_c.
    Eigen::Matrix<double, 1, 6> jacobian;
    jacobian.head<3>() = -n_c.transpose();
    jacobian.tail<3>() = n_c.cross(q_c).transpose();
    r->push_back(n_c.dot(q_c - p_c) * inv_sigma);
    J->push_back(jacobian * inv_sigma);
    information_.noalias() += J->back().transpose() * J->back();
    // J = n_c^T A with A = [-I, [q_c]x]: a tilt error of n_c (covariance normal_var (I - n n^T))
    // adds A^T cov A / sigma^2 to the expected J^T J without fixing anything.
    Eigen::Matrix<double, 3, 6> A;
    A.leftCols<3>() = -Mat3::Identity();
    A.rightCols<3>() << 0, -q_c.z(), q_c.y(), q_c.z(), 0, -q_c.x(), -q_c.y(), q_c.x(), 0;
    const Mat3 tilt = a.normal_var * (Mat3::Identity() - n_c * n_c.transpose());
    normal_noise_information_.noalias() += (inv_sigma * inv_sigma) * A.transpose() * tilt * A;
  }
}

}  // namespace rgbdslam

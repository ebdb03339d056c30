// writeTrajectoryPlot: the PNG summary of an evaluation, drawn with OpenCV.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "rgbdslam/eval/trajectory_eval.h"
#include "rgbdslam/image/codec.h"

namespace rgbdslam {
namespace {

// Layout [px].
constexpr int kImageWidth = 1200;
constexpr int kImageHeight = 600;
constexpr int kPanelWidth = kImageWidth / 2;
constexpr int kMarginTop = 60;
constexpr int kMarginBottom = 90;
constexpr int kMarginLeftTop = 30;   // top-view panel (no axis labels)
constexpr int kMarginLeftSide = 80;  // height panel (tick labels on the left)
constexpr int kMarginRight = 30;
constexpr double kPadding = 0.05;   // fraction of the data range added on each side
constexpr double kMinRange = 1e-3;  // [m] or [s]: smallest range shown, for flat data

const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kGrey(200, 200, 200);
const cv::Scalar kGroundTruthColour(180, 110, 0);  // BGR: blue
const cv::Scalar kEstimateColour(0, 0, 220);       // BGR: red
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kFontScale = 0.5;

const char* const kAxisNames[3] = {"x", "y", "z"};

struct Range {
  double lo = 0.0;
  double hi = 0.0;
  double size() const { return hi - lo; }
  double mid() const { return 0.5 * (lo + hi); }
};

// Range of the values, padded, at least kMinRange wide.
Range paddedRange(const std::vector<double>& values) {
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  Range r{*lo, *hi};
  const double pad = std::max(kPadding * r.size(), 0.5 * kMinRange);
  return Range{r.lo - pad, r.hi + pad};
}

// 1, 2 or 5 times a power of ten, at most max_value.
double niceLength(double max_value) {
  const double power = std::pow(10.0, std::floor(std::log10(max_value)));
  for (const double mantissa : {5.0, 2.0, 1.0}) {
    if (mantissa * power <= max_value) return mantissa * power;
  }
  return power;
}

std::string formatNumber(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%g", std::abs(value) < 1e-12 ? 0.0 : value);
  return buffer;
}

void putText(cv::Mat& image, const std::string& text, cv::Point origin,
             const cv::Scalar& colour = kBlack) {
  cv::putText(image, text, origin, kFont, kFontScale, colour, 1, cv::LINE_AA);
}

// The trajectories as plot data: time-sorted positions and times, the estimate aligned.
struct PlotData {
  std::vector<Vec3> gt_positions;
  std::vector<double> gt_times;
  std::vector<Vec3> est_positions;  // S_gt_est * p_est
  std::vector<double> est_times;
};

PlotData makePlotData(const Trajectory& groundtruth, const Trajectory& estimate,
                      const Sim3& S_gt_est) {
  auto sorted = [](const Trajectory& trajectory) {
    Trajectory copy = trajectory;
    std::stable_sort(copy.begin(), copy.end(),
                     [](const TimedPose& a, const TimedPose& b) { return a.t < b.t; });
    return copy;
  };
  PlotData data;
  for (const TimedPose& pose : sorted(groundtruth)) {
    data.gt_positions.push_back(pose.T_w_c.translation());
    data.gt_times.push_back(pose.t);
  }
  for (const TimedPose& pose : sorted(estimate)) {
    data.est_positions.push_back(S_gt_est * pose.T_w_c.translation());
    data.est_times.push_back(pose.t);
  }
  return data;
}

// Axes ordered by decreasing extent of the ground truth (ties by axis index).
std::array<int, 3> axesByExtent(const std::vector<Vec3>& positions) {
  Vec3 lo = Vec3::Constant(0.0);
  Vec3 hi = Vec3::Constant(0.0);
  if (!positions.empty()) lo = hi = positions.front();
  for (const Vec3& p : positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 extent = hi - lo;
  std::array<int, 3> axes = {0, 1, 2};
  std::stable_sort(axes.begin(), axes.end(), [&](int a, int b) { return extent[a] > extent[b]; });
  return axes;
}

// Maps data coordinates into a pixel rectangle (y up).
struct Mapping {
  cv::Rect area;
  Range x;
  Range y;
  double px_per_x = 1.0;
  double px_per_y = 1.0;

  cv::Point operator()(double u, double v) const {
    return cv::Point(
        static_cast<int>(std::lround(area.x + 0.5 * area.width + (u - x.mid()) * px_per_x)),
        static_cast<int>(std::lround(area.y + 0.5 * area.height - (v - y.mid()) * px_per_y)));
  }
};

void drawCurve(cv::Mat& image, const Mapping& map, const std::vector<double>& u,
               const std::vector<double>& v, const cv::Scalar& colour) {
  std::vector<cv::Point> points;
  for (size_t k = 0; k < u.size(); ++k) points.push_back(map(u[k], v[k]));
  if (points.size() == 1) cv::circle(image, points.front(), 2, colour, cv::FILLED, cv::LINE_AA);
  if (points.size() > 1) cv::polylines(image, points, false, colour, 2, cv::LINE_AA);
}

void drawLegend(cv::Mat& image, cv::Point origin, const std::string& estimate_label) {
  cv::line(image, origin, origin + cv::Point(30, 0), kGroundTruthColour, 2, cv::LINE_AA);
  putText(image, "ground truth", origin + cv::Point(38, 5));
  const cv::Point second = origin + cv::Point(160, 0);
  cv::line(image, second, second + cv::Point(30, 0), kEstimateColour, 2, cv::LINE_AA);
  putText(image, estimate_label, second + cv::Point(38, 5));
}

void drawScaleBar(cv::Mat& image, const Mapping& map) {
  const double length_m = niceLength(0.3 * map.area.width / map.px_per_x);
  const int length_px = static_cast<int>(std::lround(length_m * map.px_per_x));
  const cv::Point start(map.area.x + 10, map.area.br().y - 15);
  const cv::Point end = start + cv::Point(length_px, 0);
  cv::line(image, start, end, kBlack, 2);
  cv::line(image, start + cv::Point(0, -5), start + cv::Point(0, 5), kBlack, 2);
  cv::line(image, end + cv::Point(0, -5), end + cv::Point(0, 5), kBlack, 2);
  putText(image, formatNumber(length_m) + " m", start + cv::Point(0, -10));
}

std::vector<double> component(const std::vector<Vec3>& points, int axis) {
  std::vector<double> values;
  for (const Vec3& p : points) values.push_back(p[axis]);
  return values;
}

std::vector<double> concat(std::vector<double> a, const std::vector<double>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

void drawTopView(cv::Mat& image, const PlotData& data, int axis_u, int axis_v) {
  Mapping map;
  map.area = cv::Rect(kMarginLeftTop, kMarginTop, kPanelWidth - kMarginLeftTop - kMarginRight,
                      kImageHeight - kMarginTop - kMarginBottom);
  const auto gt_u = component(data.gt_positions, axis_u);
  const auto gt_v = component(data.gt_positions, axis_v);
  const auto est_u = component(data.est_positions, axis_u);
  const auto est_v = component(data.est_positions, axis_v);
  map.x = paddedRange(concat(gt_u, est_u));
  map.y = paddedRange(concat(gt_v, est_v));
  map.px_per_x = map.px_per_y =
      std::min(map.area.width / map.x.size(), map.area.height / map.y.size());

  cv::rectangle(image, map.area, kGrey, 1);
  drawCurve(image, map, gt_u, gt_v, kGroundTruthColour);
  drawCurve(image, map, est_u, est_v, kEstimateColour);
  drawScaleBar(image, map);
  putText(image,
          std::string("top view: ") + kAxisNames[axis_u] + " right, " + kAxisNames[axis_v] +
              " up [m] (plane of largest extent)",
          cv::Point(kMarginLeftTop, kMarginTop - 12));
}

void drawTicks(cv::Mat& image, const Mapping& map) {
  const double step_x = niceLength(map.x.size() / 4.0);
  for (double x = std::ceil(map.x.lo / step_x) * step_x; x <= map.x.hi; x += step_x) {
    const cv::Point p = map(x, map.y.lo);
    cv::line(image, p, p + cv::Point(0, 5), kBlack, 1);
    putText(image, formatNumber(x), p + cv::Point(-10, 20));
  }
  const double step_y = niceLength(map.y.size() / 4.0);
  for (double y = std::ceil(map.y.lo / step_y) * step_y; y <= map.y.hi; y += step_y) {
    const cv::Point p = map(map.x.lo, y);
    cv::line(image, p, p + cv::Point(-5, 0), kBlack, 1);
    putText(image, formatNumber(y), p + cv::Point(-kMarginLeftSide + 5, 5));
  }
}

void drawHeightOverTime(cv::Mat& image, const PlotData& data, int axis_h) {
  Mapping map;
  map.area = cv::Rect(kPanelWidth + kMarginLeftSide, kMarginTop,
                      kPanelWidth - kMarginLeftSide - kMarginRight,
                      kImageHeight - kMarginTop - kMarginBottom);
  const double t0 = std::min(data.gt_times.empty() ? 0.0 : data.gt_times.front(),
                             data.est_times.empty() ? 0.0 : data.est_times.front());
  auto relative = [t0](std::vector<double> times) {
    for (double& t : times) t -= t0;
    return times;
  };
  const auto gt_t = relative(data.gt_times);
  const auto est_t = relative(data.est_times);
  const auto gt_h = component(data.gt_positions, axis_h);
  const auto est_h = component(data.est_positions, axis_h);
  map.x = paddedRange(concat(gt_t, est_t));
  map.y = paddedRange(concat(gt_h, est_h));
  map.px_per_x = map.area.width / map.x.size();
  map.px_per_y = map.area.height / map.y.size();

  cv::rectangle(image, map.area, kGrey, 1);
  drawTicks(image, map);
  drawCurve(image, map, gt_t, gt_h, kGroundTruthColour);
  drawCurve(image, map, est_t, est_h, kEstimateColour);
  putText(image, std::string(kAxisNames[axis_h]) + " [m] over time [s] (remaining axis)",
          cv::Point(kPanelWidth + kMarginLeftSide, kMarginTop - 12));
  putText(image, "time [s]", cv::Point(map.area.x + map.area.width / 2 - 30, map.area.br().y + 40));
}

bool hasPngExtension(const std::string& path) {
  if (path.size() < 4) return false;
  std::string ext = path.substr(path.size() - 4);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".png";
}

}  // namespace

Status writeTrajectoryPlot(const std::string& png_path, const Trajectory& groundtruth,
                           const Trajectory& estimate, const EvalResult& result) {
  if (!hasPngExtension(png_path)) return Error{png_path + ": plot file name must end in .png"};
  if (groundtruth.empty() || estimate.empty())
    return Error{png_path + ": nothing to plot (empty trajectory)"};
  const PlotData data = makePlotData(groundtruth, estimate, result.S_gt_est);
  std::array<int, 3> axes = axesByExtent(data.gt_positions);
  std::sort(axes.begin(), axes.begin() + 2);  // plane axes in x, y, z order

  cv::Mat image(kImageHeight, kImageWidth, CV_8UC3, kWhite);
  drawTopView(image, data, axes[0], axes[1]);
  drawHeightOverTime(image, data, axes[2]);
  const bool similarity = result.alignment == AlignmentKind::kSimilarity;
  char title[160];
  std::snprintf(title, sizeof(title),
                "ATE RMSE %.4f m, %s alignment (scale %.4f), %zu of %zu poses associated",
                result.ate_m.rmse, similarity ? "similarity" : "rigid", result.S_gt_est.scale,
                result.num_associated, result.num_estimate);
  putText(image, title, cv::Point(kMarginLeftTop, 25));
  drawLegend(image, cv::Point(kMarginLeftTop + 10, kImageHeight - 30),
             similarity ? "estimate (similarity-aligned)" : "estimate (rigidly aligned)");
  if (Status written = writePngFile(png_path, image); !written) return Error{"cannot write plot: " + written.error()};
  return {};
}

}  // namespace rgbdslam

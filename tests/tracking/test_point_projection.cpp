// Which map points the tracker searches (point_projection.h): the viewing-direction bound.
#include "rgbdslam/tracking/point_projection.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "rgbdslam/tracking/map_replica.h"

namespace rgbdslam {
namespace {

PinholeCamera viewAngleCamera() {
  PinholeCamera c;
  c.width = 320, c.height = 240;
  c.fx = c.fy = 250.0, c.cx = 160.0, c.cy = 120.0;
  return c;
}

// Looking from 'centre' at 'target', the camera's y axis as near world y as it goes.
SE3 lookingAt(const Vec3& centre, const Vec3& target) {
  const Vec3 z = (target - centre).normalized(), x = Vec3(0, 1, 0).cross(z).normalized(), y = z.cross(x);
  Mat3 R_w_c;
  R_w_c << x, y, z;
  return SE3(R_w_c, centre);
}

// A keyframe away from the world's origin, turned, with one point off its optical axis, seen
// from a camera looking at the point along a ray 'angle_deg' off the keyframe's ray to it.
bool searchedFrom(double angle_deg, double max_view_angle_deg) {
  const PinholeCamera camera = viewAngleCamera();
  MapReplica replica(camera);
  KeyframeData data;
  data.id = 0;
  data.T_w_c = SE3(Eigen::AngleAxisd(0.4, Vec3(0.2, 1.0, 0.1).normalized()).toRotationMatrix(), Vec3(1.0, -0.5, 2.0));
  data.grey = cv::Mat(camera.height, camera.width, CV_8UC1);
  cv::randu(data.grey, 0, 255);
  replica.addKeyframe(makeKeyframe(data, KeyframeBuildOptions{}));
  const Vec3 p_src(0.3, -0.2, 2.0);  // in the keyframe's camera
  const Vec3 p_w = data.T_w_c * p_src;
  const Eigen::Vector2d uv_src = *camera.project(p_src);
  NewPoint point;
  point.point = MapPoint(MapPointData{0, p_w, 0, uv_src, 0});
  point.measurement = Measurement{0, uv_src, 0, p_src.z()};
  replica.addProvisionalPoint(point);

  // The keyframe's ray to the point, turned by the angle about an axis across it.
  const Vec3 ray = (p_w - data.T_w_c.translation()).normalized();
  const Vec3 axis = ray.cross(Vec3(0, 1, 0)).normalized();
  const Vec3 turned = Eigen::AngleAxisd(angle_deg * M_PI / 180.0, axis) * ray;
  const SE3 T_c_w = lookingAt(p_w - 2.0 * turned, p_w).inverse();
  std::vector<KeyframeView> views;
  makeKeyframeViews(replica.map(), T_c_w, &views);
  ProjectionOptions options;
  options.max_view_angle_deg = max_view_angle_deg;
  return projectPoint(camera, T_c_w, views, options, &replica.slots().front());
}

TEST(PointProjection, APointSeenFromTooFarAroundItsSourceViewIsNotSearched) {
  EXPECT_TRUE(searchedFrom(0.0, 60.0));
  EXPECT_TRUE(searchedFrom(45.0, 60.0));
  EXPECT_TRUE(searchedFrom(-45.0, 60.0));
  EXPECT_TRUE(searchedFrom(55.0, 60.0));
  EXPECT_FALSE(searchedFrom(65.0, 60.0));
  EXPECT_FALSE(searchedFrom(-65.0, 60.0));
  EXPECT_FALSE(searchedFrom(45.0, 30.0));
  EXPECT_TRUE(searchedFrom(65.0, 0.0));  // 0: no bound
}

// The cold keyframes' culling (sphereMayBeInView) never hides a point inView would count:
// random spheres, each filled with points on its surface and inside, from random poses;
// and it does cull (the control): most spheres behind or beside the camera are skipped.
TEST(PointProjection, ASphereCulledHasNoPointInView) {
  cv::RNG rng(7);
  for (const bool distorted : {false, true}) {
    PinholeCamera camera = viewAngleCamera();
    if (distorted) camera.k1 = -0.2;
    int culled = 0, missed = 0;
    for (int trial = 0; trial < 2000; ++trial) {
      const Vec3 centre(rng.uniform(-6.0, 6.0), rng.uniform(-6.0, 6.0), rng.uniform(-6.0, 6.0));
      const double radius = rng.uniform(0.0, 2.0);
      const SE3 T_c_w(Eigen::AngleAxisd(rng.uniform(-3.0, 3.0), Vec3(rng.uniform(-1.0, 1.0), 1.0, rng.uniform(-1.0, 1.0)).normalized())
                          .toRotationMatrix(),
                      Vec3(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)));
      const bool may = sphereMayBeInView(camera, T_c_w, centre, radius, ProjectionOptions{});
      culled += may ? 0 : 1;
      if (may) continue;
      for (int k = 0; k < 200; ++k) {
        const Vec3 direction = Vec3(rng.gaussian(1.0), rng.gaussian(1.0), rng.gaussian(1.0)).normalized();
        const double r = k % 2 ? radius : radius * rng.uniform(0.0, 1.0);  // on the surface, inside
        missed += inView(camera, T_c_w, centre + r * direction, ProjectionOptions{}) ? 1 : 0;
      }
    }
    EXPECT_EQ(missed, 0) << (distorted ? "distorted" : "pinhole");
    EXPECT_GT(culled, distorted ? 600 : 1200) << (distorted ? "distorted: behind only" : "pinhole");
  }
}

}  // namespace
}  // namespace rgbdslam

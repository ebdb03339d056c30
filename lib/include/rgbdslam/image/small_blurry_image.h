#pragma once
// PTAM's small blurry image (SBI). Why: a 1/16-size, heavily blurred, zero-mean copy of a
// frame is cheap to compare and align as a whole. The tracker aligns the previous frame's
// SBI with the current one to pre-estimate the inter-frame rotation before the patch
// search (large rotations would otherwise fall outside the search radius), and the
// relocaliser compares the current SBI with every keyframe's to find where it is.
//
// Call order: makeSmallBlurryImage(pyramid) once per frame (and keep it for keyframes) ->
// zmssd(a, b) to rank keyframes, or alignSmallBlurryImages(previous, current) ->
// rotationFromSe2(se2, camera, sbi.scale) -> the rotation prior for the tracker. A coarse
// alignment first: halveSmallBlurryImage of both -> alignSmallBlurryImages ->
// fullResolutionSe2 -> the start of the full-resolution alignment.
//
// Frames and units: SBI pixel coordinates [SBI px] with (0, 0) at the centre of the
// top-left pixel, x right, y down; an SBI pixel covers 16 x 16 level-0 pixels, so
// u_sbi = (u_0 + 0.5) * scale - 0.5 with scale = 1/16 (pyramid.h's convention). Values are
// grey levels (0..255 before the mean is removed).
#include <opencv2/core.hpp>

#include "rgbdslam/camera/pinhole_camera.h"
#include "rgbdslam/geometry/se3.h"
#include "rgbdslam/image/pyramid.h"

namespace rgbdslam {

constexpr int kSbiLevel = 4;             // the SBI has the size of pyramid level 4 (1/16)
constexpr double kSbiBlurSigma = 2.5;    // Gaussian blur [SBI px], as PTAM
constexpr int kSbiAlignIterations = 10;  // default ESM iterations

struct SmallBlurryImage {
  // CV_32FC1, 1/16 of the input size (40x30 for 640x480), Gaussian blurred by normalised
  // convolution (no invented border: near the edge only pixels inside are averaged), zero
  // mean [grey levels].
  cv::Mat image;
  cv::Mat grad_x;   // CV_32FC1, d image / dx by central differences [grey levels / SBI px]
  cv::Mat grad_y;   // CV_32FC1, d image / dy
  // CV_32FC1, the fraction of the blur kernel that fell inside the image: 1 in the interior,
  // about 0.5 on the edges. The alignment trusts pixels by it.
  cv::Mat support;
  double scale = 1.0 / (1 << kSbiLevel);  // SBI px per level-0 px
  // False after compactSmallBlurryImage: only 'image' is held.
  bool complete() const { return !grad_x.empty(); }
};

// Built from the coarsest pyramid level (halved until it is at level kSbiLevel). The
// pyramid needs at least one level.
SmallBlurryImage makeSmallBlurryImage(const ImagePyramid& pyramid);
// The same into an existing SBI, reusing its buffers when the size is unchanged.
void makeSmallBlurryImage(const ImagePyramid& pyramid, SmallBlurryImage* out);

// Keeps only 'image' (a quarter of the memory: a keyframe holds its SBI for relocalisation
// as long as it is in the map, and the gradients and support follow from the image).
void compactSmallBlurryImage(SmallBlurryImage* sbi);
// Puts back what compactSmallBlurryImage dropped, exactly as makeSmallBlurryImage made it
// (a no-op on a complete SBI). alignSmallBlurryImages needs complete SBIs; zmssd does not.
void restoreSmallBlurryImage(SmallBlurryImage* sbi);

// Zero-mean SSD of two SBIs of the same size: sum over pixels of
// ((a - mean a) - (b - mean b))^2 [grey levels^2]. Smaller is more similar.
double zmssd(const SmallBlurryImage& a, const SmallBlurryImage& b);

// A rotation by theta about the SBI centre c = ((cols-1)/2, (rows-1)/2) followed by a
// translation: x_to = R(theta) (x_from - c) + c + t, with R(theta) = [cos -sin; sin cos]
// acting on (x right, y down), so a positive theta turns +x towards +y (clockwise on
// screen).
struct Se2 {
  double theta = 0.0;  // [rad]
  double tx = 0.0;     // [SBI px]
  double ty = 0.0;     // [SBI px]
};

// The SBI at half its resolution (each pixel the mean of 2 x 2; an odd last row or column
// is left out, so the mean may be a little off zero: the alignment's bias takes it), with
// its gradients and support (complete), scale halved; empty when a side is under 2 px.
// 'sbi' may be compact. Why: the relocaliser ranks a lost frame's shortlist on these first
// (relocaliser.h): a quarter of the pixels, and the SBI's blur (sigma kSbiBlurSigma
// [SBI px]) leaves little detail that halving loses.
SmallBlurryImage halveSmallBlurryImage(const SmallBlurryImage& sbi);

// The Se2 'half' found between two halved SBIs (halveSmallBlurryImage) as a warp between the
// SBIs of size 'full' they were halved from. Half pixel x_h is full pixel 2 x_h + 0.5.
Se2 fullResolutionSe2(const Se2& half, cv::Size full);

// ESM (efficient second-order minimisation) Gauss-Newton on (theta, tx, ty) and a
// brightness bias b, minimising sum_x w(x) (to(W(x)) - from(x) - b)^2 over the pixels x of
// 'from' whose warp W(x) (the Se2 above) falls inside 'to'; w down-weights pixels within a
// few pixels of either image's edge (see SmallBlurryImage::support). Starts from 'start'
// (the identity by default) with no bias; stops after 'iterations' or when the update is
// negligible. The result maps scene points from their pixel in 'from' to their pixel in
// 'to'. final_error (optional) receives the weighted mean squared residual [grey levels^2];
// infinite when the overlap left is too small to fit (a warp that wandered off).
Se2 alignSmallBlurryImages(const SmallBlurryImage& from, const SmallBlurryImage& to,
                           int iterations = kSbiAlignIterations, double* final_error = nullptr,
                           const Se2& start = Se2{});

// The camera rotation that moves image points like se2 does. 'from' is the old camera and
// 'to' the new one; the returned SE3 is T_old_new (zero translation), so the new camera's
// pose is T_w_new = T_w_old * T_old_new and a bearing d_old in the old camera is seen in
// the new camera as d_new = T_old_new.rotation()^-1 * d_old. Fitted in closed form (Kabsch)
// to the bearings of a 3x3 grid of SBI pixels and their images under se2, unprojected with
// full_res_camera (level 0); sbi_scale is SmallBlurryImage::scale.
SE3 rotationFromSe2(const Se2& se2, const PinholeCamera& full_res_camera, double sbi_scale);

}  // namespace rgbdslam

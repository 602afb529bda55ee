#pragma once
// ZED-like calibrations shared by the camera tests, the OpenCV reference
// test and the camera benchmark. The factory file is modelled on real ZED
// (120 mm) files: the HD and FHD numbers are those of a published ZED
// (SN21531), 2K and VGA scaled from them as the camera's modes scale, plus
// the keys and sections real files also hold ([MISC], [IMU]-like sections,
// extra distortion keys) that the reader must skip.
#include <string>

#include <Eigen/Core>

#include "drivers/camera/stereo_calibration.hpp"

namespace rtfuse::test {

inline std::string realistic_zed_file() {
  return "[LEFT_CAM_2K]\n"
         "cx=1103.59\n"
         "cy=641.43\n"
         "fx=1398.68\n"
         "fy=1398.68\n"
         "k1=-0.176359\n"
         "k2=0.029149\n"
         "k3=-0.000911\n"
         "p1=0.000361254\n"
         "p2=-0.000543264\n"
         "\n"
         "[LEFT_CAM_FHD]\n"
         "cx=959.873\n"
         "cy=576.67\n"
         "fx=1398.68\n"
         "fy=1398.68\n"
         "k1=-0.176359\n"
         "k2=0.029149\n"
         "k3=-0.000911\n"
         "p1=0.000361254\n"
         "p2=-0.000543264\n"
         "\n"
         "[LEFT_CAM_HD]\n"
         "cx=638.437\n"
         "cy=376.835\n"
         "fx=699.34\n"
         "fy=699.34\n"
         "k1=-0.176359\n"
         "k2=0.029149\n"
         "k3=-0.000911\n"
         "p1=0.000361254\n"
         "p2=-0.000543264\n"
         "\n"
         "[LEFT_CAM_VGA]\n"
         "cx=333.718\n"
         "cy=196.917\n"
         "fx=349.67\n"
         "fy=349.67\n"
         "k1=-0.176359\n"
         "k2=0.029149\n"
         "k3=-0.000911\n"
         "p1=0.000361254\n"
         "p2=-0.000543264\n"
         "\n"
         "[RIGHT_CAM_2K]\n"
         "cx=1110.32\n"
         "cy=573.25\n"
         "fx=1401.57\n"
         "fy=1401.57\n"
         "k1=-0.174367\n"
         "k2=0.0280189\n"
         "k3=-0.000437\n"
         "p1=-0.000190735\n"
         "p2=-0.000897378\n"
         "\n"
         "[RIGHT_CAM_FHD]\n"
         "cx=966.608\n"
         "cy=508.49\n"
         "fx=1401.57\n"
         "fy=1401.57\n"
         "k1=-0.174367\n"
         "k2=0.0280189\n"
         "k3=-0.000437\n"
         "p1=-0.000190735\n"
         "p2=-0.000897378\n"
         "\n"
         "[RIGHT_CAM_HD]\n"
         "cx=641.804\n"
         "cy=342.745\n"
         "fx=700.784\n"
         "fy=700.784\n"
         "k1=-0.174367\n"
         "k2=0.0280189\n"
         "k3=-0.000437\n"
         "p1=-0.000190735\n"
         "p2=-0.000897378\n"
         "\n"
         "[RIGHT_CAM_VGA]\n"
         "cx=335.402\n"
         "cy=179.872\n"
         "fx=350.392\n"
         "fy=350.392\n"
         "k1=-0.174367\n"
         "k2=0.0280189\n"
         "k3=-0.000437\n"
         "p1=-0.000190735\n"
         "p2=-0.000897378\n"
         "\n"
         "[STEREO]\n"
         "Baseline=119.997\n"
         "CV_2K=0.0125461\n"
         "CV_FHD=0.0125461\n"
         "CV_HD=0.0125461\n"
         "CV_VGA=0.0125461\n"
         "RX_2K=-0.00903268\n"
         "RX_FHD=-0.00903268\n"
         "RX_HD=-0.00903268\n"
         "RX_VGA=-0.00903268\n"
         "RZ_2K=-0.00163963\n"
         "RZ_FHD=-0.00163963\n"
         "RZ_HD=-0.00163963\n"
         "RZ_VGA=-0.00163963\n"
         "TY=0.00157105\n"
         "TZ=0.00237081\n"
         "\n"
         "[MISC]\n"
         "Sensor_ID=0\n"
         "\n"
         "[STEREO_DISTO]\n"
         "k4=0.0\n";
}

// The file's HD or VGA numbers as a StereoCalibration, written out by hand
// (independent of the reader), in OpenCV's convention.
inline drivers::StereoCalibration zed_like_hd() {
  drivers::StereoCalibration c;
  c.width = 1280;
  c.height = 720;
  c.left = {699.34, 699.34, 638.437, 376.835, -0.176359, 0.029149, 0.000361254, -0.000543264, -0.000911};
  c.right = {700.784, 700.784, 641.804, 342.745, -0.174367, 0.0280189, -0.000190735, -0.000897378, -0.000437};
  c.rotation = Eigen::Vector3d(-0.00903268, 0.0125461, -0.00163963);
  c.translation = Eigen::Vector3d(-119.997, -0.00157105, -0.00237081) * 1e-3;
  return c;
}

inline drivers::StereoCalibration zed_like_vga() {
  drivers::StereoCalibration c;
  c.width = 672;
  c.height = 376;
  c.left = {349.67, 349.67, 333.718, 196.917, -0.176359, 0.029149, 0.000361254, -0.000543264, -0.000911};
  c.right = {350.392, 350.392, 335.402, 179.872, -0.174367, 0.0280189, -0.000190735, -0.000897378, -0.000437};
  c.rotation = Eigen::Vector3d(-0.00903268, 0.0125461, -0.00163963);
  c.translation = Eigen::Vector3d(-119.997, -0.00157105, -0.00237081) * 1e-3;
  return c;
}

// A pair far less aligned than any factory ZED: eyes turned ~0.1 rad from
// each other and a baseline 10 mm off the x axis.
inline drivers::StereoCalibration rotated_vga() {
  drivers::StereoCalibration c = zed_like_vga();
  c.rotation = Eigen::Vector3d(0.04, -0.09, 0.035);
  c.translation = Eigen::Vector3d(-0.118, 0.008, -0.006);
  return c;
}

}  // namespace rtfuse::test

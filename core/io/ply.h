// PLY point clouds and Stanford range images (ascii, binary_little_endian, binary_big_endian).
//
// Stanford range grid: `element range_grid` (num_rows*num_cols cells, each a list of 0 or 1 vertex
// indices) with `obj_info num_cols N` / `obj_info num_rows M`. The grid is row-major and its first
// row is the BOTTOM of the image (checked on the Stanford bunny: the vertical coordinate y grows
// with the file row, correlation +0.9998). Scan row 0 is the top (as for panoramas), so file row
// k becomes Scan row M-1-k; the writer flips back. A triangulation grid's line of sight is not
// spherical, so such scans get no angular grid (Scan::angles stays empty).
//
// Without a range grid the cloud is organized by spherical projection around the origin
// (OrganizeCloudByDensity) and gets that grid's angles.
#pragma once

#include <filesystem>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"

namespace scanreg::io {

// Vertex properties x, y, z (float or double) and optionally one of intensity, scalar_intensity,
// reflectance, confidence (uchar values are divided by 255, ushort by 65535; default 0.5), and
// colour from red green blue (or r g b, diffuse_red ...: uchar as is, ushort / 257, float / double
// in [0, 1] times 255).
// `obj_info scanreg_world_from_scan <16 numbers, row-major>` sets the pose (identity otherwise);
// with `obj_info scanreg_points_in_world 1` the points are in world coordinates and are taken back
// to the scanner frame with that pose (in double). With a range_grid, the vertices no cell names
// first (later returns, points without a cell) become the scan's list_points.
Expected<Scan> ReadPly(const std::filesystem::path& path, ProgressSink& progress, const CancelToken& cancel);

// Organized binary little-endian PLY: vertex x y z (double, WORLD coordinates: world_from_scan
// applied, so that every other reader places the points where they are registered) and intensity
// (float) of the valid cells, red green blue (uchar) when the scan has colour, range_grid in the Stanford convention, obj_info num_cols / num_rows /
// scanreg_world_from_scan / scanreg_points_in_world 1 (and scanreg_angular_grid 1 when the scan had
// angles; they are re-estimated on reading). A scan with points off its grid (list_points) is
// written as a plain list of every point, without range_grid (PCL's reader keeps only the vertices
// a cell names); reading organizes it again. Read back by ReadPly, the scan is the same (points
// in its scanner frame, the pose). Atomic.
Status WritePly(const std::filesystem::path& path, const Scan& scan, ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg::io

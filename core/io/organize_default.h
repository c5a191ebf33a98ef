// Organizing an unorganized cloud when the file gives no grid: the grid follows the data's own
// angular resolution, so that (nearly) every point keeps a cell of its own.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/geometry/organize.h"
#include "core/geometry/scan.h"

namespace scanreg::io {

// Points are in the scanner frame (scanner at the origin). Candidate grids are compared by the
// number of points they keep, counting exact repeats of a point once:
//  1. Rings: when the elevations form well-separated clusters (the lasers of a multi-beam lidar,
//     the lines of a TLS scan), one row per cluster at its median elevation, and columns at the
//     median azimuth step between neighbouring points of a ring (or a few times finer when that
//     keeps clearly more points). Taken when it keeps >= 99 %.
//  2. Otherwise uniform grids finer than the point spacing (isotropic, and anisotropic from the
//     azimuth step within elevation bands), coarsest first: the first that keeps >= 99.5 %, else
//     the one that keeps most.
// A point whose cell is taken may move to a free cell of its row nearby (same azimuth order). No
// grid has more than 4 cells per point; columns cover only the data's azimuth range when it is
// under half a turn. Points without a cell stay in the scan's list_points (reported with their
// count); when more than 1 % of the distinct points have none, the cloud was not seen from one
// place: single_viewpoint is false and a warning says so. `source` names
// the file (or file and scan) in messages. Error when the cloud has no usable point. However few
// points the grid keeps (a cloud merged from many stations), no point is lost. colour, time and sensor are
// empty or one per point; each point keeps its own.
Expected<Scan> OrganizeCloudByDensity(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& reflectance,
                                      std::string name, const std::string& source,
                                      const std::vector<Rgb>& colour = {}, const std::vector<double>& time = {},
                                      const std::vector<Eigen::Vector3f>& sensor = {});

// Exposed for tests: the ring grid of step 1 at the data's own azimuth step; row_elevations_rad
// is empty when the elevations do not form rings.
OrganizeOptions RingGridOptions(const std::vector<Eigen::Vector3f>& points);

// Exposed for tests: the mean angular spacing (radians) of the points over the occupied part of
// the (azimuth, elevation) plane; 0 when the cloud has no usable point.
double DensityAngularStep(const std::vector<Eigen::Vector3f>& points);

}  // namespace scanreg::io

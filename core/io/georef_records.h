// What a project records of its georeferencing (issue 15): the control points, the targets found
// or picked in the scans, and the residuals of the last adjustment — so that the CLI, the GUI and
// the report show them without re-running, and the user's names and check points are kept.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/io/control_file.h"

namespace scanreg::io {

// A target seen in one scan.
struct TargetRecord {
  std::string scan;           // scan name
  std::string name;           // control point name, or "t<k>" for a target no control point ties
  bool named_by_user = false;  // the user named it: the name ties it to control and is kept
  // "sphere": found by its geometry; "checker": a checkerboard found in the reflectance;
  // "picked": placed by the user
  std::string kind = "sphere";
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // scanner frame, metres
  double sigma_m = 0.001;     // standard deviation of the centre
  double rms_m = 0;           // fit RMS (spheres)
  int points = 0;             // fitted points (spheres)
  double residual_m = -1;     // |pose * centre - adjusted target| after the adjustment (-1: none)
};

struct ControlResidualRecord {
  std::string name;
  std::string role;  // "used", "check", "blunder", "not found"
  Eigen::Vector3d delta = Eigen::Vector3d::Zero();  // control minus adjusted target: E, N, H
  double leave_one_out_m = -1;
  int observations = 0;
};

// The last adjustment. The project's poses are in the control frame while it is present; it is
// dropped when a registration or an edit moves the scans without georeferencing them again.
struct GeorefRecord {
  double rms_m = 0;        // 3D RMS over the used control points
  int used = 0;            // control points that placed the project
  int targets = 0;         // distinct targets in the scans
  double tolerance_m = 0;  // the tolerance the residuals were graded against
  std::vector<ControlResidualRecord> control;
};

}  // namespace scanreg::io

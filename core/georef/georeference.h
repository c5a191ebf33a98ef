// Georeferencing (issue 15, item 2 and 4): a registered project placed in the survey's coordinate
// system from targets seen in the scans and control points measured by a total station or GNSS.
//
// 1. Target observations (a centre in a scan's frame) are put in the registration frame with the
//    scans' poses; observations of different scans within match_tolerance_m are one target.
// 2. Targets are tied to control points by name (picked or named by the user) or else by the
//    constellation: the rigid motion under which the most targets land on control points, found
//    from triangles of matching side lengths.
// 3. One least-squares adjustment (Ceres) of every scan pose and target position: the scan-to-scan
//    links (as the pose graph, Cauchy kernel), target observations and control coordinates, each
//    weighted by its sigma, and the levelling of levelled scans. The datum comes from control: no scan is held fixed. Solved around the
//    control points' mean so that coordinates of thousands of kilometres keep their precision.
// 4. Blunders (data snooping): while at least 4 control points place the project, the adjustment is
//    run leaving each out in turn; its residual (control minus the target the others place) is
//    tested against its covariance (the adjustment's, Ceres, plus the point's sigma). The worst
//    beyond chi-square(3) at 1 - 0.001 / n whose residual also exceeds the tolerance is left out (named,
//    with its check residual) and the test repeats. A blunder is found, not spread over the others;
//    an end point that geometry alone places loosely is not mistaken for one.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/io/control_file.h"

namespace scanreg::georef {

struct TargetObservation {
  int scan = 0;                                      // index into the pose list
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // scanner frame, metres
  double sigma_m = 0.001;                            // standard deviation of the centre
  std::string name;  // the target's name when the user gave one (a control name ties it); empty: matched
};

struct ScanLink {
  int parent = 0, child = 0;  // indices into the pose list
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
};

struct GeorefOptions {
  double match_tolerance_m = 0.2;         // one target / a control match within this (after registration)
  double default_control_sigma_m = 0.005;  // for control points without their own sigma
  double min_observation_sigma_m = 0.001;  // floor on a target centre's sigma
  // A scan-to-scan link's accuracy: dense ICP links are within ~2 mm / 0.005° on the simulated
  // street (scanreg-bench --section register); targets seen by only one or two scans leave the
  // rotations to the links, so they must not be held looser than they are.
  double link_translation_sigma_m = 0.002;
  double link_rotation_sigma_rad = 1e-4;
  // Levelled scans (item 3): each scan's vertical (its z axis, or the file pose's, see Georeference)
  // is the control frame's within this (radians), as a tilt compensator gives (a few arc seconds to
  // 0.01°). 0: not levelled; then the control points' spread alone fixes the tilt (σ / spread: 2 mm
  // over a 5 m wide street is 0.02°).
  double levelled_sigma_rad = 0;
  double tolerance_m = 0.01;  // control residual tolerance: green < tolerance/2 <= orange <= tolerance < red
  bool detect_blunders = true;
  // Scanners stand upright within a degree or two (levelled by bubble or compensator), and so does
  // the root scan's frame: a constellation match that tips its vertical over by more than this is a
  // mirror image of the targets, not the survey. 180: no check (scans mounted at any angle).
  double max_tilt_deg = 3.0;

  Status Validate() const;
};

enum class ControlRole {
  kUsed,      // places the project
  kCheck,     // the user's check point: compared only
  kBlunder,   // left out: its residual against the others exceeded the tolerance
  kNotFound,  // no target in the scans matches it
};
const char* ControlRoleName(ControlRole role);  // "used", "check", "blunder", "not found"

enum class Grade { kGreen, kOrange, kRed };
Grade GradeOf(double residual_m, double tolerance_m);
const char* GradeName(Grade grade);  // "green", "orange", "red"

struct ControlResidual {
  std::string name;
  ControlRole role = ControlRole::kNotFound;
  Eigen::Vector3d delta = Eigen::Vector3d::Zero();  // control minus adjusted target (E, N, H), metres
  double leave_one_out_m = -1;  // residual when the adjustment leaves it out (-1: not measured: < 4 used)
  int observations = 0;         // scans that saw the target
  double residual_m() const { return delta.norm(); }
};

struct GeorefResult {
  std::vector<Eigen::Isometry3d> world_from_scan;  // in the control frame
  std::vector<std::string> observation_target;     // per observation: the control name, or "t<k>"
  std::vector<double> observation_residual_m;      // per observation: |pose * centre - target|
  std::vector<ControlResidual> control;            // in the order of the control points
  double rms_m = 0;  // 3D RMS over the used control points
  int used = 0;
  int targets = 0;  // distinct targets found in the scans
};

// held[i]: scan i is kept as placed relative to the others (a hand placement): it moves with the
// datum only. up_in_scan[i]: for levelled scans (options.levelled_sigma_rad), scan i's vertical in
// its own frame as its file's pose gives it (the tilt compensator's pitch and roll); empty or a
// zero vector: its z axis. Errors: bad options, an observation naming a missing scan, fewer than 3 control
// points tied to targets (naming how many were found), control points on one line, cancel.
Expected<GeorefResult> Georeference(const std::vector<Eigen::Isometry3d>& world_from_scan,
                                    const std::vector<ScanLink>& links,
                                    const std::vector<TargetObservation>& observations,
                                    const std::vector<io::ControlPoint>& control, const GeorefOptions& options,
                                    const CancelToken& cancel, const std::vector<bool>& held = {},
                                    const std::vector<Eigen::Vector3d>& up_in_scan = {});

}  // namespace scanreg::georef

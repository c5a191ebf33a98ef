// scanreg-cli simulate / demo: a simulated scan project written as PTX (or E57) files and a project file.
#include <cmath>
#include <cstdio>

#include "app/cli_commands.h"
#include "app/cli_util.h"
#include "core/pipeline/create_project.h"
#include "core/pipeline/project_scans.h"

namespace scanreg::cli {
namespace {

const std::vector<OptionSpec> kSimulateOptions = {
    {"stations", true, false, "N        number of scan stations (default 11)"},
    {"spacing", true, false, "METRES   distance between stations (default 5)"},
    {"size", true, false, "WxH      panorama columns x rows (default 3000x750)"},
    {"noise", true, false, "METRES   range noise sigma along the line of sight (default 0.012)"},
    {"angle-noise", true, false, "DEG      sigma of each beam's angle noise (default 0)"},
    {"noise-growth", true, false, "M/M      range noise sigma added per metre of range (default 0; 1e-4 = +1 cm at 100 m)"},
    {"traffic", true, false, "N        N moving vehicles and 2N pedestrians around each station, new in every scan (default 0)"},
    {"seed", true, false, "S        random seed (default 1)"},
    {"scene", true, false, "street|windows|city|office|office-identical   scene kind (default street); city: a grid of "
                           "blocks whose streets close loops, grown to hold the stations; office: a corridor with "
                           "same-size rooms behind regular doors, half the stations in the corridor SPACING apart, "
                           "each other one in a room in front of its door; office-identical: every room alike, the "
                           "floor symmetric (city and office: no targets, traffic or far station)"},
    {"far-station", false, false, "       add one station far away (no overlap)"},
    {"no-reflectance", false, false, "       write a constant reflectance of 0.5 (as some exporters do): geometry only"},
    {"sphere-targets", true, false, "N        N sphere targets (145 mm) on tripods along the street, and DIR/control.csv "
                                    "with their control coordinates (default 0)"},
    {"checker-targets", true, false, "N        N checkerboard targets (20 cm) on the façades along the street, in "
                                     "DIR/control.csv too (default 0)"},
    {"control-noise", true, false, "METRES   sigma per axis of the control coordinates (default 0.002)"},
    {"tilt", true, false, "DEG      largest tilt of a station from upright (default 0.5; 0: levelled scans)"},
    {"utm", false, false, "       place the project at UTM-sized coordinates (E 512 km, N 5 402 km, H 100 m, grid "
                          "turned 30°): reference poses and control in that frame"},
    {"format", true, false, "ptx|e57  scan files written (default ptx; e57: binary, valid points only, about half "
                           "the disk)"},
    {"out", true, false, "DIR      output folder (required for simulate)"},
};

Expected<pipeline::ScanFileFormat> ReadScanFormat(const Args& args) {
  const std::string format = args.Get("format").value_or("ptx");
  if (format == "ptx") return pipeline::ScanFileFormat::kPtx;
  if (format == "e57") return pipeline::ScanFileFormat::kE57;
  return MakeError(ErrorCode::kInvalidArgument, "--format must be 'ptx' or 'e57', not '" + format + "'");
}

// Reads the simulation options shared by `simulate` and `demo`.
Expected<SimulatedProjectOptions> ReadSimulationOptions(const Args& args, std::pair<int, int> default_size,
                                                        int default_stations) {
  SimulatedProjectOptions options;
  auto stations = args.GetInt("stations", default_stations, 1, 200);
  if (!stations) return stations.error();
  auto spacing = args.GetDouble("spacing", 5.0, 0.5, 100.0);
  if (!spacing) return spacing.error();
  auto size = args.GetSize("size", default_size);
  if (!size) return size.error();
  auto noise = args.GetDouble("noise", 0.012, 0.0, 1.0);
  if (!noise) return noise.error();
  auto angle_noise = args.GetDouble("angle-noise", 0.0, 0.0, 1.0);
  if (!angle_noise) return angle_noise.error();
  auto growth = args.GetDouble("noise-growth", 0.0, 0.0, 0.01);
  if (!growth) return growth.error();
  auto traffic = args.GetInt("traffic", 0, 0, 200);
  if (!traffic) return traffic.error();
  auto seed = args.GetInt("seed", 1, 0, 1 << 30);
  if (!seed) return seed.error();
  const std::string scene = args.Get("scene").value_or("street");
  if (scene != "street" && scene != "windows" && scene != "city" && scene != "office" && scene != "office-identical") {
    return MakeError(ErrorCode::kInvalidArgument,
                     "--scene must be 'street', 'windows', 'city', 'office' or 'office-identical', not '" + scene + "'");
  }
  options.stations = *stations;
  options.spacing_m = *spacing;
  options.scanner.cols = size->first;
  options.scanner.rows = size->second;
  options.scanner.range_noise_m = *noise;
  options.scanner.angle_noise_deg = *angle_noise;
  options.scanner.range_noise_per_m = *growth;
  options.traffic.vehicles = *traffic;
  options.traffic.pedestrians = 2 * *traffic;
  options.seed = static_cast<std::uint64_t>(*seed);
  options.scanner.seed = options.seed;
  options.scene.seed = options.seed;
  options.scene.kind = scene == "windows"            ? SceneOptions::Kind::kRepeatedWindows
                       : scene == "city"             ? SceneOptions::Kind::kCity
                       : scene == "office"           ? SceneOptions::Kind::kOffice
                       : scene == "office-identical" ? SceneOptions::Kind::kOfficeIdentical
                                          : SceneOptions::Kind::kStreet;
  options.add_far_station = args.Has("far-station");
  options.scanner.reflectance = !args.Has("no-reflectance");
  auto targets = args.GetInt("sphere-targets", 0, 0, 1000);
  if (!targets) return targets.error();
  auto control_noise = args.GetDouble("control-noise", 0.002, 0.0, 1.0);
  if (!control_noise) return control_noise.error();
  auto tilt = args.GetDouble("tilt", 0.5, 0.0, 20.0);
  if (!tilt) return tilt.error();
  auto checkers = args.GetInt("checker-targets", 0, 0, 1000);
  if (!checkers) return checkers.error();
  options.sphere_targets = *targets;
  options.checker_targets = *checkers;
  options.control_noise_m = *control_noise;
  options.max_tilt_deg = *tilt;
  if (args.Has("utm")) {
    options.control_from_world.linear() = Eigen::AngleAxisd(30.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    options.control_from_world.translation() = Eigen::Vector3d(512345.678, 5401234.567, 100.25);
  }
  if (Status s = options.Validate(); !s) return s.error();
  return options;
}

void PrintProjectSummary(const io::Project& project) {
  std::printf("project %s: %zu scans\n", project.file.string().c_str(), project.scans.size());
  std::printf("  %-6s %-28s %10s %10s %10s %8s\n", "scan", "file", "x (m)", "y (m)", "z (m)", "yaw (°)");
  for (const io::ProjectScan& s : project.scans) {
    const Eigen::Isometry3d t = s.reference_world_from_scan.value_or(s.world_from_scan);
    const double yaw = std::atan2(t.linear()(1, 0), t.linear()(0, 0)) * 180.0 / M_PI;
    std::printf("  %-6s %-28s %10.3f %10.3f %10.3f %8.2f\n", s.name.c_str(), s.path.filename().string().c_str(),
                t.translation().x(), t.translation().y(), t.translation().z(), yaw);
  }
}

}  // namespace

int RunSimulate(const std::vector<std::string>& argv) {
  int code = 0;
  auto args = ParseOrHelp("simulate", "--out DIR [options]   (writes DIR/*.ptx or *.e57 and DIR/project.scanreg.json)", argv,
                          kSimulateOptions, &code);
  if (!args) return code;
  if (!args->positional().empty()) {
    return Fail(MakeError(ErrorCode::kInvalidArgument, "simulate: unexpected argument '" + args->positional()[0] + "'"));
  }
  const auto out = args->Get("out");
  if (!out) return Fail(MakeError(ErrorCode::kInvalidArgument, "simulate: --out DIR is required"));
  auto options = ReadSimulationOptions(*args, {3000, 750}, 11);
  if (!options) return Fail(options.error());
  auto format = ReadScanFormat(*args);
  if (!format) return Fail(format.error());
  TerminalProgress progress;
  CancelToken& cancel = InterruptToken();
  auto project = pipeline::WriteSimulatedProject(*options, *out, progress, cancel, *format);
  if (!project) return Fail(project.error());
  PrintProjectSummary(*project);
  std::printf("reference poses are the true poses; scans are unregistered (identity header pose)\n");
  if (options->sphere_targets + options->checker_targets > 0) {
    std::printf("control points of the targets: %s (register --control it)\n",
                (project->file.parent_path() / "control.csv").string().c_str());
  }
  return 0;
}

int RunDemo(const std::vector<std::string>& argv) {
  int code = 0;
  auto args = ParseOrHelp("demo", "[--out DIR] [options]   simulate a street project, register it, write the merged mesh and the report",
                          argv, kSimulateOptions, &code);
  if (!args) return code;
  const std::string out = args->Get("out").value_or("scanreg-demo");
  auto options = ReadSimulationOptions(*args, {1500, 375}, 6);
  if (!options) return Fail(options.error());
  auto format = ReadScanFormat(*args);
  if (!format) return Fail(format.error());
  TerminalProgress progress;
  CancelToken& cancel = InterruptToken();
  std::printf("simulating a %d-station street project (%dx%d, noise %.1f mm) in %s\n", options->stations,
              options->scanner.cols, options->scanner.rows, options->scanner.range_noise_m * 1000, out.c_str());
  auto project = pipeline::WriteSimulatedProject(*options, out, progress, cancel, *format);
  if (!project) return Fail(project.error());
  PrintProjectSummary(*project);
  std::printf("\nregistering (coarse 3D RANSAC + dense ICP, loop checks)...\n");
  pipeline::RegisterOptions register_options;
  register_options.range_sigma_m = options->scanner.range_noise_m;
  register_options.feature_cache_dir = pipeline::ProjectCacheDir(*project);
  const int status = RegisterAndReport(*project, register_options, false);
  if (status != 0 && status != 3) return status;
  // The merged surface of the registered scans: TSDF (S's ML distance takes minutes on a street),
  // 10 cm voxels, returns within 25 m of their scanner.
  const std::string mesh = (project->file.parent_path() / "merged.ply").string();
  std::printf("\nmerging the registered scans into %s ...\n", mesh.c_str());
  const int merged = RunMerge({project->file.string(), "--method", "tsdf", "--voxel", "0.1", "--max-range", "25", "--out", mesh});
  if (merged != 0) return merged;
  // The registration report a surveyor signs off: evidence per link, errors against the truth.
  const std::string report = (project->file.parent_path() / "report").string();
  std::printf("\nwriting the registration report into %s ...\n", report.c_str());
  if (const int reported = RunReport({project->file.string(), "--out", report}); reported != 0) return reported;
  std::printf("\nproject saved: %s\n", project->file.string().c_str());
  return status;
}

}  // namespace scanreg::cli

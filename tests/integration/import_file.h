// A file imported as a user imports it (`scanreg-cli new`, then a command that reads the scans),
// and the simulated stations the readers' tests write, for the tests of what other programs read.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <optional>
#include <vector>

#include "core/pipeline/create_project.h"
#include "core/pipeline/project_scans.h"
#include "core/simulate/project_sim.h"

namespace scanreg {

struct Imported {
  io::Project project;
  std::vector<Scan> scans;
};

// One file made into a project in `dir` and its scans loaded, as `scanreg-cli new` and a later command do.
inline std::optional<Imported> ImportFile(const std::filesystem::path& file, const std::filesystem::path& dir) {
  NullProgress progress;
  CancelToken cancel;
  pipeline::CreateProjectOptions create;
  create.scan_files = {file};
  Expected<pipeline::CreatedProject> created = pipeline::CreateProject(dir / "p.scanreg.json", create, progress, cancel);
  EXPECT_TRUE(created.ok()) << created.error().ToString();
  if (!created.ok()) return std::nullopt;
  auto scans = pipeline::LoadProjectScans(created->project, progress, cancel);
  EXPECT_TRUE(scans.ok()) << scans.error().ToString();
  if (!scans.ok()) return std::nullopt;
  return Imported{created->project, std::move(*scans)};
}

// Two simulated street stations 6 m apart, 600 × 150, with their true poses.
inline Expected<std::vector<Scan>> TwoStreetStations() {
  SimulatedProjectOptions o;
  o.stations = 2;
  o.spacing_m = 6;
  o.scanner.cols = 600;
  o.scanner.rows = 150;
  o.seed = o.scanner.seed = o.scene.seed = 9;
  NullProgress progress;
  return SimulateProject(o, progress, CancelToken());
}

}  // namespace scanreg

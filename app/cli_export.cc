// scanreg-cli export-clouds: the registered scans as PTX / E57 / PLY files, poses kept or applied.
#include <cstdio>

#include "app/cli_commands.h"
#include "app/cli_util.h"
#include "core/pipeline/export_clouds.h"

namespace scanreg::cli {

int RunExportClouds(const std::vector<std::string>& argv) {
  int code = 0;
  auto args = ParseOrHelp(
      "export-clouds", "PROJECT.scanreg.json --out DIR [--format ptx|e57|ply|las] [--apply-poses]", argv,
      {{"out", true, false, "DIR      output folder: one file per registered scan, DIR/<scan>.<format>"},
       {"format", true, false,
        "ptx|e57|ply|las   file format (default ptx); ply and las always hold world\n"
        "                     coordinates in double precision (las: 0.1 mm, LAS 1.4 format 6)"},
       {"apply-poses", false, false,
        "       ptx, e57: write world coordinates (pose applied to the points, identity pose in the header);\n"
        "                     default: points in the scanner frame, the registered pose kept in the header (lossless;\n"
        "                     applied world coordinates are floats: a warning names each scan rounded by > 0.1 mm)"}},
      &code);
  if (!args) return code;
  if (args->positional().size() != 1) {
    return Fail(MakeError(ErrorCode::kInvalidArgument, "export-clouds: give exactly one project file"));
  }
  const auto out = args->Get("out");
  if (!out) return Fail(MakeError(ErrorCode::kInvalidArgument, "export-clouds: --out DIR is required"));
  pipeline::ExportCloudsOptions options;
  options.dir = *out;
  options.format = args->Get("format").value_or("ptx");
  options.apply_poses = args->Has("apply-poses");
  if (Status s = options.Validate(); !s) return Fail(MakeError(s.error().code, "export-clouds: " + s.error().message));
  auto project = io::LoadProject(args->positional()[0]);
  if (!project) return Fail(project.error());
  TerminalProgress progress;
  CancelToken& cancel = InterruptToken();
  auto exported = pipeline::ExportClouds(*project, options, progress, cancel);
  if (!exported) return Fail(MakeError(exported.error().code, "export-clouds: " + exported.error().message));
  int written = 0;
  for (const pipeline::ExportedScan& e : *exported) {
    if (e.file.empty()) {
      std::printf("skipped %s: %s\n", e.name.c_str(), e.skipped.c_str());
    } else {
      std::printf("wrote %s: %zu points -> %s\n", e.name.c_str(), e.points, e.file.c_str());
      ++written;
    }
  }
  std::printf("exported %d of %zu scans (%s, %s)\n", written, exported->size(), options.format.c_str(),
              pipeline::WorldFormat(options.format) ? "world coordinates in double precision"
              : options.apply_poses                 ? "poses applied to the points"
                                                    : "poses kept in the header");
  return 0;
}

}  // namespace scanreg::cli

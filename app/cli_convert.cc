// scanreg-cli convert IN OUT: between scan formats, keeping the grid, reflectance and pose.
#include <cstdio>

#include "app/cli_commands.h"
#include "app/cli_util.h"
#include "core/io/e57_reader.h"
#include "core/io/output_paths.h"
#include "core/io/scan_file.h"
#include "core/io/text_parse.h"

namespace scanreg::cli {

int RunConvert(const std::vector<std::string>& argv) {
  int code = 0;
  auto args = ParseOrHelp("convert", "IN OUT   (formats by extension: .ptx, .e57, .ply, .pcd; IN also .las)", argv,
                          {{"scan", true, true, "NAME     .e57 input: convert only this scan (repeatable)"}}, &code);
  if (!args) return code;
  if (args->positional().size() != 2) {
    return Fail(MakeError(ErrorCode::kInvalidArgument, "convert: give an input and an output file"));
  }
  const std::filesystem::path in = args->positional()[0], out = args->positional()[1];
  if (Status s = io::CheckNotAnInput(out, {in}, "convert: OUT"); !s) return Fail(s.error());
  std::error_code ec;
  if (std::filesystem::exists(out, ec) && std::filesystem::equivalent(in, out, ec)) {
    return Fail(MakeError(ErrorCode::kInvalidArgument,
                          "convert: input and output are the same file; input files are never modified"));
  }
  TerminalProgress progress;
  CancelToken& cancel = InterruptToken();
  if (args->Has("scan") && io::LowerExtension(in) != ".e57") {
    return Fail(MakeError(ErrorCode::kInvalidArgument, "convert: --scan chooses scans of an .e57 input only"));
  }
  io::E57ReadOptions chosen;
  chosen.names = args->GetAll("scan");
  auto scans =
      chosen.names.empty() ? io::ReadScanFile(in, progress, cancel) : io::ReadE57(in, chosen, progress, cancel);
  if (!scans) return Fail(scans.error());
  if (Status s = io::WriteScanFile(out, *scans, progress, cancel); !s) return Fail(s.error());
  std::size_t points = 0;
  for (const Scan& s : *scans) points += s.CountPoints();
  std::printf("converted %zu scan(s), %zu points: %s -> %s\n", scans->size(), points, in.c_str(), out.c_str());
  return 0;
}

const std::vector<Command>& Commands() {
  static const std::vector<Command> commands = {
      {"demo", "the built-in demo: simulate a street project, register it, write the merged mesh and the report",
       RunDemo},
      {"simulate", "simulate a TLS project: PTX scans + project with true reference poses", RunSimulate},
      {"register", "register every scan of a project automatically (W pipeline)", RunRegister},
      {"pair-job", "run one pair job of a registration planned with register --plan (e.g. one task of a Slurm array)",
       RunPairJob},
      {"merge", "merge the registered scans into one surface (ML distance or TSDF) and write a mesh", RunMerge},
      {"new", "create a project from PTX / E57 / PLY / PCD scan files", RunNew},
      {"info", "list a project's scans: size, valid %, pose, status", RunInfo},
      {"link", "accept or reject a link (a weak link placing a scan that is not verified): register keeps the decision", RunLink},
      {"report", "write the registration report: HTML page with the confusion matrix, network, links, poses, errors",
       RunReport},
      {"export-poses",
       "write world_from_scan poses as JSON, CloudCompare 4x4 .txt files or a CSV of positions and angles",
       RunExportPoses},
      {"export-clouds", "write the registered scans as PTX / E57 / PLY, poses kept in the header or applied",
       RunExportClouds},
      {"convert", "convert a scan file between PTX, E57, PLY and PCD", RunConvert},
  };
  return commands;
}

}  // namespace scanreg::cli

// scanreg-cli report: the registration report of a saved project as an HTML page with pictures.
#include <cstdio>

#include "app/cli_commands.h"
#include "app/cli_util.h"
#include "core/report/report.h"

namespace scanreg::cli {

int RunReport(const std::vector<std::string>& argv) {
  int code = 0;
  auto args = ParseOrHelp("report", "PROJECT.scanreg.json --out DIR   (writes DIR/index.html and its PNG pictures)",
                          argv, {{"out", true, false, "DIR      report folder (created when missing)"}}, &code);
  if (!args) return code;
  if (args->positional().size() != 1) {
    return Fail(MakeError(ErrorCode::kInvalidArgument, "report: give exactly one project file"));
  }
  const auto out = args->Get("out");
  if (!out) return Fail(MakeError(ErrorCode::kInvalidArgument, "report: --out DIR is required"));
  auto project = io::LoadProject(args->positional()[0]);
  if (!project) return Fail(project.error());
  TerminalProgress progress;
  CancelToken& cancel = InterruptToken();
  auto index = report::WriteReport(*project, *out, progress, cancel);
  if (!index) return Fail(index.error());
  int registered = 0;
  for (const io::ProjectScan& s : project->scans) registered += s.registered;
  std::printf("wrote %s (%d of %zu scans registered, %zu links)\n", index->string().c_str(), registered,
              project->scans.size(), project->links.size());
  return 0;
}

}  // namespace scanreg::cli

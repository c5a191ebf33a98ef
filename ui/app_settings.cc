#include "ui/app_settings.h"

#include <QDir>
#include <QFileInfo>
#include <QSettings>

namespace scanreg::ui {
namespace {

constexpr char kLastDir[] = "paths/last_dir";
constexpr char kRecent[] = "recent/projects";

void SetRecentProjects(const QStringList& list) { QSettings().setValue(kRecent, list); }

}  // namespace

QString LastDir() {
  const QString dir = QSettings().value(kLastDir).toString();
  return !dir.isEmpty() && QFileInfo(dir).isDir() ? dir : QDir::homePath();
}

void RememberDir(const QString& path) {
  const QFileInfo info(path);
  QSettings().setValue(kLastDir, info.isDir() ? info.absoluteFilePath() : info.absolutePath());
}

QStringList RecentProjects() { return QSettings().value(kRecent).toStringList(); }

void AddRecentProject(const QString& path) {
  const QString absolute = QFileInfo(path).absoluteFilePath();
  QStringList list = RecentProjects();
  list.removeAll(absolute);
  list.prepend(absolute);
  while (list.size() > kMaxRecentProjects) list.removeLast();
  SetRecentProjects(list);
}

QStringList RemoveMissingRecentProjects() {
  QStringList kept, missing;
  for (const QString& path : RecentProjects()) (QFileInfo::exists(path) ? kept : missing) << path;
  if (!missing.isEmpty()) SetRecentProjects(kept);
  return missing;
}

}  // namespace scanreg::ui

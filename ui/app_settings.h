// What the application remembers between sessions (QSettings): the folder of the last file
// dialog and the recent projects. Window layout and the merge options are kept by their owners
// (MainWindow, MergePanel) under "window/" and "merge/".
#pragma once

#include <QString>
#include <QStringList>

namespace scanreg::ui {

// The folder the last file dialog was in (the home folder at first).
QString LastDir();
// Remembers the folder of `path` (a file or a folder) for the next file dialog.
void RememberDir(const QString& path);

constexpr int kMaxRecentProjects = 8;
// Most recent first, at most kMaxRecentProjects, absolute paths.
QStringList RecentProjects();
void AddRecentProject(const QString& path);
// Drops the projects whose file no longer exists; returns the dropped ones.
QStringList RemoveMissingRecentProjects();

}  // namespace scanreg::ui

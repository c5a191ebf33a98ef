// The project document (issue 14 item 1): edits are undoable snapshots, the dirty state follows
// the undo stack (undo back to the saved state is clean), an edit that asks for a rerun takes the
// rerun's result into the same undo step, and scans added are not undoable.
#include <QSignalSpy>
#include <QUndoStack>
#include <QtTest/QtTest>

#include "ui/project_document.h"

using scanreg::Scan;
using scanreg::io::Project;
using scanreg::io::ProjectScan;
using scanreg::ui::ProjectDocument;

namespace {

Project TwoScans() {
  Project p;
  p.file = "/tmp/doc.scanreg.json";
  for (const char* name : {"a", "b"}) {
    ProjectScan s;
    s.name = name;
    p.scans.push_back(s);
  }
  return p;
}

std::vector<scanreg::pipeline::ScanPreview> Points(int n) {
  std::vector<scanreg::pipeline::ScanPreview> scans;
  for (int i = 0; i < n; ++i) scans.push_back(scanreg::pipeline::MakePreview(Scan("s" + std::to_string(i), 2, 2), 4));
  return scans;
}

}  // namespace

class ProjectDocumentTest : public QObject {
  Q_OBJECT

 private slots:
  void UndoBackToTheSavedStateIsClean() {
    ProjectDocument doc;
    doc.Open(TwoScans(), Points(2));
    QVERIFY(!doc.dirty());
    QSignalSpy dirty(&doc, &ProjectDocument::DirtyChanged);
    Project moved = doc.project();
    moved.scans[1].world_from_scan.translation() = Eigen::Vector3d(1, 2, 3);
    doc.Edit("move b", moved);
    QVERIFY(doc.dirty());
    // The scans' poses follow the project's (stored once, synced by the document).
    QCOMPARE(doc.previews()[1].scan.world_from_scan.translation().x(), 1.0);
    doc.undoStack()->undo();
    QVERIFY(!doc.dirty());
    QCOMPARE(doc.previews()[1].scan.world_from_scan.translation().x(), 0.0);
    QCOMPARE(dirty.count(), 2);
    doc.undoStack()->redo();
    doc.MarkSaved("/tmp/doc.scanreg.json", 42);
    QVERIFY(!doc.dirty());
    doc.undoStack()->undo();  // before the save: differs from the file
    QVERIFY(doc.dirty());
    QCOMPARE(doc.project().disk_digest, std::uint64_t(42));  // where it lives is not part of an edit
  }

  void AnEditsRerunResultIsTheSameUndoStep() {
    ProjectDocument doc;
    doc.Open(TwoScans(), Points(2));
    QSignalSpy rerun(&doc, &ProjectDocument::RerunRequested);
    Project overridden = doc.project();
    overridden.scans[1].parent_override = "a";
    doc.Edit("register b to a", overridden, true);
    QCOMPARE(rerun.count(), 1);
    Project registered = doc.project();
    registered.scans[1].registered = true;
    doc.ApplyRegistration("register the scans", registered, Eigen::MatrixXi::Ones(2, 2));
    QCOMPARE(doc.undoStack()->count(), 1);
    QVERIFY(doc.project().scans[1].registered);
    QCOMPARE(doc.confusion().rows(), 2);
    doc.undoStack()->undo();  // the override and its result go together
    QVERIFY(!doc.project().scans[1].parent_override.has_value());
    QVERIFY(!doc.project().scans[1].registered);
    QCOMPARE(doc.confusion().rows(), 0);
    doc.undoStack()->redo();
    QCOMPARE(rerun.count(), 1);  // a redo restores the result without running again
    QVERIFY(doc.project().scans[1].registered);
    // A registration of its own (Register all) is a step of its own.
    doc.ApplyRegistration("register the scans", doc.project(), Eigen::MatrixXi::Zero(2, 2));
    QCOMPARE(doc.undoStack()->count(), 2);
  }

  void AddedScansAreNotUndoableAndLeaveTheProjectDirty() {
    ProjectDocument doc;
    doc.Open(TwoScans(), Points(2));
    doc.Edit("touch", doc.project());
    QSignalSpy added(&doc, &ProjectDocument::ScansChanged);
    Project three = doc.project();
    ProjectScan c;
    c.name = "c";
    three.scans.push_back(c);
    doc.AppendScans(three, Points(1));
    QCOMPARE(added.count(), 1);
    QCOMPARE(int(doc.previews().size()), 3);
    QVERIFY(!doc.undoStack()->canUndo());  // snapshots with fewer scans no longer apply
    QVERIFY(doc.dirty());
    doc.MarkSaved("/tmp/doc.scanreg.json", 7);
    QVERIFY(!doc.dirty());
  }
};

QTEST_GUILESS_MAIN(ProjectDocumentTest)
#include "project_document_test.moc"

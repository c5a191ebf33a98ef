#include "ui/distance_overlay.h"

#include <vtkActor.h>
#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkLookupTable.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkScalarBarActor.h>
#include <vtkTextProperty.h>

namespace scanreg::ui {
namespace {

vtkSmartPointer<vtkLookupTable> DistanceColours(double max_mm) {
  auto lut = vtkSmartPointer<vtkLookupTable>::New();
  lut->SetNumberOfTableValues(256);
  lut->SetHueRange(0.66, 0.0);  // blue (close) -> red (far)
  lut->SetSaturationRange(0.85, 0.85);
  lut->SetValueRange(1.0, 1.0);
  lut->SetTableRange(0.0, max_mm);
  lut->UseBelowRangeColorOn();
  lut->SetBelowRangeColor(0.55, 0.55, 0.55, 1.0);  // outside the overlap
  lut->Build();
  return lut;
}

vtkSmartPointer<vtkActor> Cloud(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& distances_m,
                                vtkLookupTable* lut) {
  const vtkIdType n = static_cast<vtkIdType>(points.size());
  auto xyz = vtkSmartPointer<vtkFloatArray>::New();
  xyz->SetNumberOfComponents(3);
  xyz->SetNumberOfTuples(n);
  auto scalars = vtkSmartPointer<vtkFloatArray>::New();
  scalars->SetName("distance_mm");
  scalars->SetNumberOfTuples(n);
  auto ids = vtkSmartPointer<vtkIdTypeArray>::New();
  ids->SetNumberOfValues(n);
  for (vtkIdType i = 0; i < n; ++i) {
    xyz->SetTypedTuple(i, points[i].data());
    // Outside the overlap (negative) stays below the range: grey.
    scalars->SetValue(i, distances_m[i] < 0 ? -1.0f : 1000.0f * distances_m[i]);
    ids->SetValue(i, i);
  }
  auto pts = vtkSmartPointer<vtkPoints>::New();
  pts->SetData(xyz);
  auto verts = vtkSmartPointer<vtkCellArray>::New();
  verts->SetData(1, ids);
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(pts);
  poly->SetVerts(verts);
  poly->GetPointData()->SetScalars(scalars);
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputData(poly);
  mapper->SetLookupTable(lut);
  mapper->SetScalarRange(lut->GetTableRange());
  mapper->SetScalarModeToUsePointData();
  mapper->ScalarVisibilityOn();
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetPointSize(2);
  return actor;
}

}  // namespace

DistanceOverlay MakeDistanceOverlay(const pipeline::PairInspection& pair, double scale_max_m) {
  DistanceOverlay overlay;
  auto lut = DistanceColours(1000.0 * scale_max_m);
  overlay.clouds.push_back(Cloud(pair.parent_points, pair.parent_distance_m, lut));
  overlay.clouds.push_back(Cloud(pair.child_points, pair.child_distance_m, lut));
  overlay.legend = vtkSmartPointer<vtkScalarBarActor>::New();
  overlay.legend->SetLookupTable(lut);
  overlay.legend->SetTitle("Distance (mm)");  // of each point to the other scan's surface
  overlay.legend->SetNumberOfLabels(6);
  overlay.legend->SetLabelFormat("%.0f");
  overlay.legend->SetMaximumWidthInPixels(110);
  overlay.legend->SetBarRatio(0.25);
  overlay.legend->SetPosition(0.86, 0.10);
  overlay.legend->SetWidth(0.12);
  overlay.legend->SetHeight(0.55);
  overlay.legend->DrawBelowRangeSwatchOn();
  overlay.legend->SetBelowRangeAnnotation("outside overlap");
  overlay.legend->UnconstrainedFontSizeOn();  // the fonts below, not scaled with the bar
  overlay.legend->SetTextPad(4);
  for (vtkTextProperty* text : {overlay.legend->GetTitleTextProperty(), overlay.legend->GetLabelTextProperty(),
                                overlay.legend->GetAnnotationTextProperty()}) {
    text->SetFontSize(13);
    text->ItalicOff();
    text->BoldOff();
    text->ShadowOff();
    text->SetColor(0.92, 0.92, 0.92);
  }
  return overlay;
}

}  // namespace scanreg::ui

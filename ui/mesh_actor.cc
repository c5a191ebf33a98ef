#include "ui/mesh_actor.h"

#include <vtkActor.h>
#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkUnsignedCharArray.h>

#include <vector>

namespace scanreg::ui {

vtkSmartPointer<vtkActor> MakeMeshActor(const merge::Mesh& mesh, const Eigen::Vector3d& scene_origin,
                                        bool scanner_colour) {
  const Eigen::Vector3f shift = (mesh.origin - scene_origin).cast<float>();
  const vtkIdType nv = static_cast<vtkIdType>(mesh.vertices.size());
  auto xyz = vtkSmartPointer<vtkFloatArray>::New();
  xyz->SetNumberOfComponents(3);
  xyz->SetNumberOfTuples(nv);
  for (vtkIdType v = 0; v < nv; ++v) {
    const Eigen::Vector3f p = mesh.vertices[v] + shift;
    xyz->SetTypedTuple(v, p.data());
  }
  // Area-weighted vertex normals: the sum of the (unnormalised) normals of the adjacent triangles.
  std::vector<Eigen::Vector3f> sums(mesh.vertices.size(), Eigen::Vector3f::Zero());
  auto ids = vtkSmartPointer<vtkIdTypeArray>::New();
  ids->SetNumberOfValues(static_cast<vtkIdType>(3 * mesh.triangles.size()));
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    const Eigen::Vector3f n =
        (mesh.vertices[tri[1]] - mesh.vertices[tri[0]]).cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]]);
    for (int k = 0; k < 3; ++k) {
      sums[tri[k]] += n;
      ids->SetValue(static_cast<vtkIdType>(3 * t + k), tri[k]);
    }
  }
  auto normals = vtkSmartPointer<vtkFloatArray>::New();
  normals->SetName("Normals");
  normals->SetNumberOfComponents(3);
  normals->SetNumberOfTuples(nv);
  for (vtkIdType v = 0; v < nv; ++v) {
    const float len = sums[v].norm();
    const Eigen::Vector3f n = len > 0 ? Eigen::Vector3f(sums[v] / len) : Eigen::Vector3f::UnitZ();
    normals->SetTypedTuple(v, n.data());
  }
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetData(xyz);
  auto polys = vtkSmartPointer<vtkCellArray>::New();
  polys->SetData(3, ids);
  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetPolys(polys);
  poly->GetPointData()->SetNormals(normals);
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputData(poly);
  mapper->ScalarVisibilityOff();
  if (scanner_colour && mesh.coloured && mesh.info.size() == mesh.vertices.size()) {
    auto rgb = vtkSmartPointer<vtkUnsignedCharArray>::New();
    rgb->SetName("Colour");
    rgb->SetNumberOfComponents(3);
    rgb->SetNumberOfTuples(nv);
    for (vtkIdType v = 0; v < nv; ++v) rgb->SetTypedTuple(v, mesh.info[v].colour.data());
    poly->GetPointData()->SetScalars(rgb);
    mapper->ScalarVisibilityOn();
    mapper->SetColorModeToDirectScalars();
  }
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  vtkProperty* property = actor->GetProperty();
  property->SetColor(0.86, 0.82, 0.74);  // warm light grey, like plaster
  property->SetSpecular(0.15);
  property->SetSpecularPower(20);
  property->BackfaceCullingOff();
  return actor;
}

}  // namespace scanreg::ui

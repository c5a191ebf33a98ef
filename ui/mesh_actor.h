// The merged mesh as a VTK actor for the 3D view: triangles with area-weighted vertex normals
// (smooth shading), drawn relative to the scene's origin like the scan clouds; in the scanners'
// colour when asked and the mesh has it (merge::Mesh::coloured), else plaster grey.
#pragma once

#include <vtkSmartPointer.h>

#include <Eigen/Core>

#include "core/merge/mesh.h"

class vtkActor;

namespace scanreg::ui {

vtkSmartPointer<vtkActor> MakeMeshActor(const merge::Mesh& mesh, const Eigen::Vector3d& scene_origin,
                                        bool scanner_colour);

}  // namespace scanreg::ui

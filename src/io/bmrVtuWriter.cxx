/*=========================================================================
 *
 *  Copyright NumFOCUS
 *
 *  Licensed under the Apache License, Version 2.0 (the "License");
 *  you may not use this file except in compliance with the License.
 *  You may obtain a copy of the License at
 *
 *         http://www.apache.org/licenses/LICENSE-2.0.txt
 *
 *  Unless required by applicable law or agreed to in writing, software
 *  distributed under the License is distributed on an "AS IS" BASIS,
 *  WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 *  See the License for the specific language governing permissions and
 *  limitations under the License.
 *
 *=========================================================================*/
#include "bmrVtuWriter.h"

#include "bmrAtomicFile.h"
#include "bmrError.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

namespace bmr {
namespace {
void
AddArrays(const std::vector<DataArray> & arrays, std::size_t count, vtkDataSetAttributes * target, const char * kind)
{
  for (const auto & a : arrays)
  {
    if (a.values.size() != count * static_cast<std::size_t>(a.components))
    {
      Fail("WriteVtu", std::string(kind) + " array \"" + a.name + "\" has the wrong number of values");
    }
    vtkNew<vtkDoubleArray> array;
    array->SetName(a.name.c_str());
    array->SetNumberOfComponents(a.components);
    array->SetNumberOfTuples(static_cast<vtkIdType>(count));
    std::copy(a.values.begin(), a.values.end(), array->GetPointer(0));
    target->AddArray(array);
  }
}
} // namespace

void
WriteVtu(const std::string &            fileName,
         const TetrahedralMesh &        mesh,
         const std::vector<DataArray> & pointData,
         const std::vector<DataArray> & cellData)
{
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(mesh.GetNumberOfPoints()));
  for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
  {
    points->SetPoint(static_cast<vtkIdType>(n), &mesh.points[3 * n]);
  }
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  grid->Allocate(static_cast<vtkIdType>(mesh.GetNumberOfTetrahedra()));
  for (std::size_t e = 0; e < mesh.GetNumberOfTetrahedra(); ++e)
  {
    const vtkIdType ids[4] = {
      mesh.tetrahedra[4 * e], mesh.tetrahedra[4 * e + 1], mesh.tetrahedra[4 * e + 2], mesh.tetrahedra[4 * e + 3]
    };
    grid->InsertNextCell(VTK_TETRA, 4, ids);
  }
  AddArrays(pointData, mesh.GetNumberOfPoints(), grid->GetPointData(), "point");
  AddArrays(cellData, mesh.GetNumberOfTetrahedra(), grid->GetCellData(), "cell");

  const std::string                    tmp = TemporaryPathFor(fileName);
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(tmp.c_str());
  writer->SetInputData(grid);
  writer->SetDataModeToAppended();
  writer->SetCompressorTypeToZLib();
  if (writer->Write() != 1)
  {
    std::remove(tmp.c_str());
    Fail("WriteVtu", "cannot write \"" + fileName + "\"");
  }
  CommitTemporaryFile(tmp, fileName);
}

} // namespace bmr

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
#ifndef itkBiomechanicalImageIO_h
#define itkBiomechanicalImageIO_h

#include "bmrAtomicFile.h"
#include "bmrError.h"
#include "itkDefaultConvertPixelTraits.h"
#include "itkDicomStructureCheck.h"
#include "itkGDCMImageIO.h"
#include "itkGDCMSeriesFileNames.h"
#include "itkGridGeometryConversion.h"
#include "itkImageFileReader.h"
#include "itkImageFileWriter.h"
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkImageSeriesReader.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <type_traits>

namespace itk {

/** Largest image ReadBiomechanicalImage() reads: 2^31 voxels (a declared size beyond is a corrupt or absurd
 * header). \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
constexpr double BiomechanicalMaximumNumberOfVoxels = 2147483648.0;

/** Throws naming the first voxel of \a image that is NaN or infinite (floating-point pixels and vectors of
 * them); \a what names the image. \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
template<typename TImage>
void
CheckImageIsFinite(const TImage * image, const std::string & what)
{
  using ValueType = typename NumericTraits<typename TImage::PixelType>::ValueType;
  if (!std::is_floating_point<ValueType>::value)
  {
    return;
  }
  const unsigned int components = NumericTraits<typename TImage::PixelType>::GetLength(image->GetPixel({}));
  for (ImageRegionConstIteratorWithIndex<TImage> it(image, image->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    for (unsigned int c = 0; c < components; ++c)
    {
      const auto value = DefaultConvertPixelTraits<typename TImage::PixelType>::GetNthComponent(c, it.Get());
      if (!std::isfinite(static_cast<double>(value)))
      {
        std::ostringstream os;
        os << what << ": voxel " << it.GetIndex() << " is not finite (NaN or infinite)";
        bmr::FailInput("CheckImageIsFinite", os.str());
      }
    }
  }
}

namespace detail {
/** Captures what an image IO prints on std::cerr while it lives. MetaIO reports a truncated data file only
 * there and returns a half-read image without throwing; the capture turns that into an error. The stream
 * buffer is swapped for the duration of one read only and restored by the destructor, also on exceptions. */
class CerrCapture
{
public:
  CerrCapture()
    : m_Old(std::cerr.rdbuf(m_Text.rdbuf()))
  {}
  ~CerrCapture() { std::cerr.rdbuf(m_Old); }
  CerrCapture(const CerrCapture &) = delete;
  CerrCapture &
  operator=(const CerrCapture &) = delete;
  std::string
  FirstLine() const
  {
    std::string t = m_Text.str();
    t.erase(0, std::min(t.size(), t.find_first_not_of(" \n\t")));
    return t.substr(0, t.find('\n'));
  }

private:
  std::ostringstream m_Text;
  std::streambuf *   m_Old;
};

template<typename TImage>
typename TImage::Pointer
ReadDicomSeries(const std::string & path, const std::string & what)
{
  CheckDicomDirectoryStructure(path, what); // GDCM's scanner parses every file; a corrupt one can abort it
  auto names = GDCMSeriesFileNames::New();
  names->SetUseSeriesDetails(true);
  names->SetDirectory(path);
  const auto & series = names->GetSeriesUIDs();
  if (series.empty())
  {
    bmr::FailInput("ReadBiomechanicalImage", what + " \"" + path + "\" is a directory without a DICOM series");
  }
  auto reader = ImageSeriesReader<TImage>::New();
  reader->SetImageIO(GDCMImageIO::New());
  reader->SetFileNames(names->GetFileNames(series.front()));
  reader->Update();
  typename TImage::Pointer image = reader->GetOutput();
  // The first slice's DICOM attributes (frame of reference, patient, study) travel with the volume.
  const auto * slices = reader->GetMetaDataDictionaryArray();
  if (slices != nullptr && !slices->empty() && slices->front() != nullptr)
  {
    image->SetMetaDataDictionary(*slices->front());
  }
  return image;
}

template<typename TImage>
typename TImage::Pointer
ReadImageFile(const std::string & path, const std::string & what)
{
  CheckDicomFileStructure(path, what); // GDCMImageIO's probe would parse a corrupt DICOM file and can abort
  auto reader = ImageFileReader<TImage>::New();
  reader->SetFileName(path);
  reader->UpdateOutputInformation();
  const unsigned int dim = reader->GetImageIO()->GetNumberOfDimensions();
  if (dim != 3)
  {
    bmr::FailInput("ReadBiomechanicalImage",
                   what + " \"" + path + "\" is " + std::to_string(dim) + "-D; a 3-D image is required");
  }
  double voxels = 1.0;
  for (unsigned int a = 0; a < dim; ++a)
  {
    voxels *= static_cast<double>(reader->GetImageIO()->GetDimensions(a));
  }
  if (voxels > BiomechanicalMaximumNumberOfVoxels)
  {
    std::ostringstream os;
    os << what << " \"" << path << "\" declares " << voxels << " voxels (more than 2^31)";
    bmr::FailInput("ReadBiomechanicalImage", os.str());
  }
  reader->Update();
  return reader->GetOutput();
}
} // namespace detail

/** Reads a 3-D image from any file ITK reads, or a DICOM series directory (GDCM). Refuses, with an
 * itk::ExceptionObject whose description names \a what and \a path in one line, images that cannot be
 * read, are not 3-D, declare more than 2^31 voxels, have a zero, negative or non-finite spacing, or hold a
 * non-finite voxel. \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
template<typename TImage>
typename TImage::Pointer
ReadBiomechanicalImage(const std::string & path, const std::string & what)
{
  typename TImage::Pointer image;
  std::string              failure;
  {
    detail::CerrCapture diagnostics;
    try
    {
      image = std::filesystem::is_directory(path) ? detail::ReadDicomSeries<TImage>(path, what)
                                                  : detail::ReadImageFile<TImage>(path, what);
    }
    catch (const ExceptionObject & e)
    {
      const std::string description = e.GetDescription();
      failure =
        description.rfind(what, 0) == 0 ? description : "cannot read " + what + " \"" + path + "\": " + description;
    }
    if (failure.empty() && !diagnostics.FirstLine().empty())
    {
      failure = "cannot read " + what + " \"" + path + "\": " + diagnostics.FirstLine();
    }
  }
  if (!failure.empty())
  {
    bmr::FailInput("ReadBiomechanicalImage", failure.substr(0, failure.find('\n')));
  }
  GridGeometryOf(image).Validate((what + " \"" + path + "\"").c_str());
  CheckImageIsFinite(image.GetPointer(), what + " \"" + path + "\"");
  return image;
}

/** The gzip level WriteImageAtomically uses by default for images of \a TImage: 1 (the fastest) for integer pixels
 * (label maps shrink about twentyfold), 0 for floating-point ones (CT, fields, dose), which gzip barely shrinks
 * (by about a tenth) for most of the write's time. */
template<typename TImage>
constexpr int
DefaultCompressionLevel()
{
  using Component = typename NumericTraits<typename TImage::PixelType>::ValueType;
  return std::is_integral<Component>::value ? 1 : 0;
}

/** Writes \a image to \a path (format by the extension; gzip at \a compressionLevel, 1 fastest ... 9 smallest, 0
 * uncompressed, where the format compresses; negative: DefaultCompressionLevel()) through a temporary
 * file renamed when complete, so that a failed write leaves no partial file. \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationIO */
template<typename TImage>
void
WriteImageAtomically(const TImage * image, const std::string & path, int compressionLevel = -1)
{
  if (compressionLevel < 0)
  {
    compressionLevel = DefaultCompressionLevel<TImage>();
  }
  const std::string tmp = bmr::TemporaryPathFor(path);
  auto              writer = ImageFileWriter<TImage>::New();
  writer->SetInput(image);
  writer->SetFileName(tmp);
  writer->SetUseCompression(compressionLevel > 0);
  if (compressionLevel > 0)
  {
    writer->SetCompressionLevel(compressionLevel);
  }
  try
  {
    writer->Update();
  }
  catch (const ExceptionObject & e)
  {
    std::remove(tmp.c_str());
    bmr::Fail("WriteImageAtomically", "cannot write \"" + path + "\": " + e.GetDescription());
  }
  bmr::CommitTemporaryFile(tmp, path);
}

} // namespace itk

#endif

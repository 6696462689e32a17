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
#ifndef itkBiomechanicalPipelines_h
#define itkBiomechanicalPipelines_h

// Whole jobs as one call, returning result structs (Doxygen group BiomechanicalRegistrationPipelines, docs/groups.dox):
// biomechreg parses, calls these, prints and writes; nothing else. One header per job; this one includes them all.
#include "itkDemonsPipeline.h"
#include "itkModulusInterval.h"
#include "itkPhantomPipeline.h"
#include "itkPipelineTypes.h"
#include "itkRegistrationPipeline.h"
#include "itkSimulationPipeline.h"

#endif

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
#include "bmrAtomicFile.h"

#include "bmrError.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <unistd.h>

namespace bmr {

std::string
TemporaryPathFor(const std::string & finalPath)
{
  const std::size_t slash = finalPath.find_last_of('/');
  const std::string dir = slash == std::string::npos ? std::string() : finalPath.substr(0, slash + 1);
  const std::string base = slash == std::string::npos ? finalPath : finalPath.substr(slash + 1);
  return dir + ".tmp-" + std::to_string(static_cast<long>(::getpid())) + "-" + base;
}

void
CommitTemporaryFile(const std::string & temporaryPath, const std::string & finalPath)
{
  if (std::rename(temporaryPath.c_str(), finalPath.c_str()) != 0)
  {
    const std::string reason = std::strerror(errno);
    std::remove(temporaryPath.c_str());
    Fail("CommitTemporaryFile", "cannot write \"" + finalPath + "\": " + reason);
  }
}

void
WriteTextFileAtomically(const std::string & path, const std::string & text)
{
  const std::string tmp = TemporaryPathFor(path);
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out)
    {
      Fail("WriteTextFileAtomically", "cannot write \"" + path + "\": " + std::strerror(errno));
    }
    out << text;
    out.close();
    if (!out)
    {
      std::remove(tmp.c_str());
      Fail("WriteTextFileAtomically", "writing \"" + path + "\" failed (disk full?)");
    }
  }
  CommitTemporaryFile(tmp, path);
}

} // namespace bmr

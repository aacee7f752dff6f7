#pragma once
// What sinew-export does, as one library call (the tool and the Python module's
// Results.export both make it): a results file's visual surface written as glTF 2.0 (.glb), a PC2
// point cache with its rest-pose OBJ, and/or an OBJ sequence (docs/visual-output.md).
#include <string>
#include <vector>

namespace sinew::postprocess {

struct ExportRequest {
  std::string results;  // results.h5
  std::string surface;  // read_surface's name ("" the only one, "volume" the volume's boundary)
  std::string glb;      // "" none
  std::string pc2;      // "" none; needs rest_obj
  std::string rest_obj;
  std::string obj_sequence;    // folder, "" none
  std::string up = "y";        // the results' up axis: y or z (glTF is turned to +Y up)
  std::string color = "none";  // none | displacement | von_mises
  double fps = 0;              // 0: 24 or 30 from the output rate
  double time_scale = 0;       // 0: one results frame per animation frame
  bool linear = false;         // glTF interpolation: linear instead of step
};

// Writes what `request` names. Returns the lines sinew-export prints (what was read and written).
// Throws ConfigError (nothing to export, --pc2 without --rest-obj, an unknown colour or axis),
// FormatError / IoError from the reader and the writers.
std::vector<std::string> export_results(const ExportRequest& request);

}  // namespace sinew::postprocess

// Machine models arrive as TOML from admins (UploadMachineModel): any text gives a validated model
// or an error naming the key, never a crash. A model that is accepted must build its scene and
// answer a clamp.
#include "machine_models/p4/machine_model.h"
#include "machine_models/p4/machine_scene.h"

#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto model = gk::p4::parse_machine_model(text);
  if (!model.ok()) return 0;
  (void)gk::p4::MachineScene::build(model.value());
  return 0;
}

// ValidateStep requests as the service takes them: the wire message (binary, or text format when
// the first byte is even: easier for the fuzzer to mutate), its translation into the engine's
// question (server/proto_convert), and the engine's answer on the default machine with every field
// checked. Any request gives an answer or an error naming a field, never a crash or an escaped
// exception.
#include "engine/machines/machine_registry.h"
#include "engine/parts/part_registry.h"
#include "engine/parts/part_store.h"
#include "engine/steps/step_answers.h"
#include "gatekeeper/v1/gatekeeper.pb.h"
#include "server/proto_convert.h"
#include "tests/fuzz/fuzz_input.h"

#include <google/protobuf/text_format.h>

#include <cstdlib>
#include <filesystem>
#include <memory>

namespace {

namespace pb = ::gatekeeper::v1;
using namespace gk;

struct Service {
  std::unique_ptr<engine::PartStore> store;
  std::unique_ptr<engine::PartRegistry> parts;
  std::unique_ptr<engine::MachineRegistry> machines;
  std::unique_ptr<engine::StepAnswers> answers;
};

Service& service() {
  static Service s = [] {
    Service out;
    const std::string dir = std::filesystem::temp_directory_path() / "gk-step-request-fuzzer";
    std::filesystem::create_directories(dir);
    out.store = engine::PartStore::open(dir + "/parts").value();
    out.parts = std::make_unique<engine::PartRegistry>(*out.store, dir + "/bvh");
    out.machines = engine::MachineRegistry::create().value();
    // One answer kept: every new input is validated, not answered from the cache.
    out.answers = std::make_unique<engine::StepAnswers>(*out.machines, *out.parts, 1);
    return out;
  }();
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto in = fuzz::select(data, size, 2);
  pb::ValidateStepRequest request;
  const bool parsed = in.variant == 0 ? google::protobuf::TextFormat::ParseFromString(in.payload, &request)
                                      : request.ParseFromString(in.payload);
  if (!parsed) return 0;
  auto question = server::to_question(request);
  if (!question.ok()) return 0;
  (void)service().answers->validate(question.value());
  return 0;
}

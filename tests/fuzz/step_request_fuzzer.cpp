// ValidateStep requests as the service takes them: the wire message (binary, or text format when
// the first byte is even: easier for the fuzzer to mutate), its translation into the engine's
// types with every field checked, and the validation itself on the default machine. Any request
// gives an answer or an error naming a field, never a crash or an escaped exception.
#include "gatekeeper/v1/gatekeeper.pb.h"
#include "machine_models/p4/step_validator.h"
#include "server/part_registry.h"
#include "server/part_store.h"
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
  std::unique_ptr<server::PartStore> store;
  std::unique_ptr<server::PartRegistry> parts;
  p4::MachineModel model;
  std::unique_ptr<p4::StepValidator> validator;
};

Service& service() {
  static Service s = [] {
    Service out;
    const std::string dir = std::filesystem::temp_directory_path() / "gk-step-request-fuzzer";
    std::filesystem::create_directories(dir);
    out.store = server::PartStore::open(dir + "/parts").value();
    out.parts = std::make_unique<server::PartRegistry>(*out.store, dir + "/bvh");
    out.model = p4::default_machine_model().value();
    out.validator = std::make_unique<p4::StepValidator>(p4::MachineScene::build(out.model).value());
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
  Service& s = service();
  auto part = server::to_part(request.part(), *s.parts);
  if (!part.ok()) return 0;
  auto step = server::to_step(request.step());
  if (!step.ok() || !p4::validate_step(s.model, step.value()).ok()) return 0;
  p4::MachineState state = p4::MachineState::with_aba_span(s.model, -1e9, 1e9, part.value().thickness_mm());
  if (request.has_state()) {
    auto st = server::to_state(request.state(), s.model);
    if (!st.ok()) return 0;
    state = st.value();
  }
  if (!s.validator->set_state(state).ok()) return 0;
  s.validator->clear_caches();
  (void)s.validator->validate(part.value(), step.value(), !request.skip_corrections());
  return 0;
}

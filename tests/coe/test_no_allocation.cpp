// The request path allocates nothing after start-up: every service below runs inside a
// CountAllocations scope (tests/support/allocation_counter.hpp).
#include <optional>

#include "coe/diagnosis_history.hpp"
#include "coe/process_image.hpp"
#include "tests/coe/sdo_fixture.hpp"
#include "tests/support/allocation_counter.hpp"

namespace rackcat::coe::test {
namespace {

TEST_F(SdoTest, RequestPathMakesNoHeapAllocation) {
  // Every request framed up-front, into buffers allocated up-front.
  std::vector<Bytes> requests;
  uint8_t c = 0;
  auto add = [&](uint8_t service, const Bytes& body) {
    c = c >= 7 ? 1 : c + 1;
    requests.push_back(coe_message(c, service, body));
  };
  add(2, upload_req(0x1018, 1));                // expedited upload
  add(2, download_expedited(0x2000, 0, 9, 1));  // expedited download
  add(2, upload_req(0x1008, 0));                // normal upload
  add(2, upload_req(0x2002, 0));                // segmented upload
  add(2, {0x60, 0, 0, 0, 0, 0, 0, 0});
  add(2, {0x70, 0, 0, 0, 0, 0, 0, 0});
  add(2, upload_req(0x1C12, 0, true));  // complete access
  add(2, download_normal(0x1C12, 0, {1, 0, 0, 0x16}, true));
  add(2, download_normal(0x2002, 0, Bytes(112, 'x'), false, 200));  // segmented download
  add(2, Bytes(1 + 88, 0x01));
  add(2, download_expedited(0x1018, 1, 1, 4));               // abort
  add(2, download_expedited(0x2009, 0, 1, 1));               // hooks
  add(8, {0x01, 0x00, 0x00, 0x00, 0x01, 0x00});              // OD list (fragmented)
  add(8, {0x03, 0x00, 0x00, 0x00, 0x18, 0x10});              // object description
  add(8, {0x05, 0x00, 0x00, 0x00, 0x18, 0x10, 0x01, 0x78});  // entry description
  add(8, {0x03, 0x00, 0x00, 0x00, 0x34, 0x12});              // info error
  add(5, {0x00});                                            // mailbox error
  const Bytes repeat = requests.front();
  requests.push_back(repeat);  // the same bytes after other requests: a new request
  int hooked = 0;
  od.find(0x2009)->edit_hooks().validate_write = [](const Object&, int, std::span<const uint8_t>,
                                                    EsmState) { return AbortCode::None; };
  od.find(0x2009)->edit_hooks().after_write = [&hooked](Object&, int) { ++hooked; };
  Bytes reply(48);
  std::vector<size_t> lengths;
  lengths.reserve(requests.size() * 8);

  if (!rackcat::testing::CountAllocations::available())
    GTEST_SKIP() << "operator new is ASan's here";
  std::optional<rackcat::testing::CountAllocations> count(std::in_place);
  auto handle = [&](auto data, size_t, auto out) {
    return server.handle(data, out, EsmState::PreOp);
  };
  auto poll_server = [&](auto out) { return server.poll(out); };
  for (const Bytes& r : requests) {
    lengths.push_back(frame.request(r, reply, handle));
    while (size_t n = frame.poll(reply, poll_server)) lengths.push_back(n);
    server.queue_emergency(0x1000, 1);
    lengths.push_back(frame.poll(reply, poll_server));
  }
  const size_t allocations = count->allocations();
  count.reset();

  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(hooked, 1);
  for (size_t n : lengths) EXPECT_GT(n, 0u);
}

TEST_F(SdoTest, CyclicPathMakesNoHeapAllocation) {
  ProcessImage image(od);
  ASSERT_EQ(image.compile(), AbortCode::None);
  Bytes sm2(image.output_bytes(), 0x5A), sm3(image.input_bytes());
  if (!rackcat::testing::CountAllocations::available())
    GTEST_SKIP() << "operator new is ASan's here";
  rackcat::testing::CountAllocations count;
  for (int i = 0; i < 1000; ++i) {
    image.write_outputs(sm2);
    image.read_inputs(sm3);
  }
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_EQ(od.find(0x7000)->get_u(2), 0x5Au);
}

// ETG.1020 diagnosis history: adding messages (wrap-around, both modes, filtered ones) and the
// SDO hooks' reads and acknowledgements run on the cyclic path without allocating.
TEST(DiagnosisHistoryAllocation, AddAndAcknowledgeMakeNoHeapAllocation) {
  ObjectDictionary dict;
  diag::History history(8);
  dict.add(history.make_object());
  history.bind(*dict.find(diag::kIndex));
  diag::Message m;
  m.diag_code = diag::emergency_diag_code(0x5000);
  m.type = diag::Type::Warning;
  m.add_u8(1);
  m.add_u16(2);
  if (!rackcat::testing::CountAllocations::available())
    GTEST_SKIP() << "operator new is ASan's here";
  rackcat::testing::CountAllocations count;
  for (int i = 0; i < 1000; ++i) {
    m.time_ns = static_cast<uint64_t>(i);
    history.add(m);
    history.on_read(history.newest_subindex());
    history.on_read(-1);
    if (i % 100 == 50) history.write_newest_acknowledged(history.newest_subindex());
    if (i == 500) history.write_flags(diag::kFlagAcknowledgeMode);
    if (i % 100 == 99) history.write_newest_acknowledged(0);
  }
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_GT(history.count(), 0u);
}

}  // namespace
}  // namespace rackcat::coe::test

// 0x10F3 diagnosis history (ETG.1020 ch. 13; behaviour in coe/diagnosis_history.hpp, attached
// by mdp::Device) and the device-level TxPDO 0x1BFF that lets a master map 0x10F3:04 "New
// Messages Available" into its process data (ETG.1020 ch. 13: the entry is TxPDO-mappable).
// 0x1BFF is not in the default 0x1C13 assignment; a master adds it in PREOP.
#include "coe/diagnosis_history.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/od_helpers.hpp"

namespace rackcat::mdp {

using namespace detail;

void add_diagnosis_objects(const RackConfig&, coe::ObjectDictionary& od) {
  od.add(coe::diag::History(kDiagnosisMessages).make_object());

  Object pdo(kDiagnosisTxPdo, ObjectCode::Record, "TxPDO Diagnosis", coe::record_type::kPdoMapping);
  pdo.add(sub0(2));
  // ETG.1000.6 §5.6.7.4.8 mapping entries: index << 16 | subindex << 8 | bit length; the
  // 7-bit gap to the byte boundary is padding (index 0, subindex 0).
  pdo.add(num(1, "SubIndex 001", DataType::Unsigned32, acc("ro"),
              (uint32_t{coe::diag::kIndex} << 16) | (0x04u << 8) | 1u));
  pdo.add(num(2, "Padding", DataType::Unsigned32, acc("ro"), 7u));
  pdo.finalize();
  od.add(std::move(pdo));
}

}  // namespace rackcat::mdp

// ENI import: a line from an EtherCAT Network Information file (ETG.2100) as configuration
// tools export it, with the devices' ESI files (ETG.2000) looked up by identity in a directory
// the user names (`rackcat run --eni FILE --esi-dir DIR`, `rackcat check --eni FILE --esi-dir
// DIR`; docs/LINE.md "ENI import").
//
// What is read of each /EtherCATConfig/Config/Slave, in file order (= line order):
//   Info/VendorId, ProductCode, RevisionNo (ETG.2100 "Slave/Info"): the device is the ESI
//     <Device> with that Vendor/Id, Type@ProductCode and Type@RevisionNo among the *.xml files
//     directly in DIR, or a Fusion.IO rack file (*.yaml in DIR) with that identity;
//     Info/SerialNo becomes the SII serial number;
//   ProcessData/RxPdo and TxPdo (ETG.2100 "ProcessData"): every PDO must be one of the ESI's,
//     entry for entry; those with an Sm attribute are the assigned ones and become the
//     device's start-up assignment (SII PDO categories, 0x1C12/0x1C13); their size must fit
//     the SM's MaxSize and equal ProcessData/Send and Recv BitLength when those are given;
//   Mailbox/CoE/InitCmds/InitCmd (ETG.2100 "CoE init commands"): the master sends them, so
//     each must name an object the device's dictionary has, writable in the state the
//     transition sends it in, with data of the entry's size.
// The ESC register InitCmds and the Cyclic frames are the master's business and are not read.
// Any problem is one device::FileError "FILE:LINE: reason" naming the ENI (or the ESI) line.
#pragma once

#include <string>

#include "apps/line/line_file.hpp"

namespace rackcat::apps {

// Throws device::FileError.
LineFile load_eni_file(const std::string& eni_path, const std::string& esi_dir);
LineFile parse_eni_file(const std::string& xml_text, const std::string& eni_path,
                        const std::string& esi_dir);

}  // namespace rackcat::apps

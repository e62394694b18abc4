//! `--mode op`: ethercrab as the configurator of a benchmark. Brings every SubDevice of a line
//! of any length up to [`OP_MAX_SUBDEVICES`] (SOEM, and with it pysoem, stops at 200) to OP
//! the way ethercrab's own examples do, with the process-data watchdog off so that the line
//! stays in OP once the master has gone, exchanges `--cycles` cycles of process data with the
//! working counter checked on every one, prints where the group's image lies and exits
//! without touching the AL state. scripts/op_bench.py captures the cyclic LRW meanwhile and
//! replays it (issue 16: 256 and 1,024 slaves in OP).

use crate::{MAX_PDI, PDU_PAYLOAD, Report, loopback, options::Options};
use ethercrab::{MainDevice, MainDeviceConfig, SubDeviceState, std::ethercat_now};
use std::time::Instant;

/// Longest line `--mode op` configures: 4,096 SubDevices, the most `rackcat run --slaves` takes.
pub const OP_MAX_SUBDEVICES: usize = 4096;

/// ESC register 0x0420, Watchdog Time Process Data (in units of the watchdog divider, 0x0400):
/// 0 turns the watchdog off, as pysoem's `set_watchdog("processdata", 0)` does.
const WATCHDOG_TIME_PROCESS_DATA: u16 = 0x0420;

pub async fn bring_to_op(md: &MainDevice<'_>, o: &Options, r: &mut Report) -> Result<(), String> {
    let t = Instant::now();
    let group = md
        .init_single_group::<OP_MAX_SUBDEVICES, MAX_PDI>(ethercat_now)
        .await
        .map_err(|e| format!("ethercrab init (discovery, SII, DC, INIT->PRE-OP): {e}"))?;
    r.pass(format!(
        "init: {} SubDevice(s) in PRE-OP in {} ms (DC static drift compensation {} frames)",
        group.len(),
        t.elapsed().as_millis(),
        MainDeviceConfig::default().dc_static_sync_iterations
    ));
    if let Some(n) = o.expect_slaves {
        if group.len() != n {
            return Err(format!("SubDevice count {} (expected {n})", group.len()));
        }
    }
    for sd in group.iter(md) {
        sd.register_write(WATCHDOG_TIME_PROCESS_DATA, 0u16)
            .await
            .map_err(|e| {
                format!(
                    "SubDevice {:#06x}: process-data watchdog off (0x0420 := 0): {e}",
                    sd.configured_address()
                )
            })?;
    }

    let group = group
        .into_pre_op_pdi(md)
        .await
        .map_err(|e| format!("PDO mapping / FMMU configuration (into_pre_op_pdi): {e}"))?;
    let (mut in_lens, mut out_lens) = (Vec::new(), Vec::new());
    for sd in group.iter(md) {
        in_lens.push(sd.inputs_raw().len());
        out_lens.push(sd.outputs_raw().len());
    }
    let expected_wkc = loopback::expected_lrw_wkc(&in_lens, &out_lens, PDU_PAYLOAD, PDU_PAYLOAD);
    let (inputs, outputs) = (
        in_lens.iter().sum::<usize>(),
        out_lens.iter().sum::<usize>(),
    );
    let group = group
        .into_safe_op(md)
        .await
        .map_err(|e| format!("PRE-OP -> SAFE-OP: {e}"))?;
    let t = Instant::now();
    let group = group
        .into_op(md)
        .await
        .map_err(|e| format!("SAFE-OP -> OP (into_op): {e}"))?;
    r.pass(format!("OP reached in {} ms", t.elapsed().as_millis()));

    let mut wrong = 0u64;
    let mut not_op = 0u64;
    for _ in 0..o.cycles {
        let resp = group.tx_rx(md).await.map_err(|e| format!("cycle: {e}"))?;
        wrong += u64::from(resp.working_counter != expected_wkc);
        not_op += u64::from(
            !resp
                .subdevice_states
                .iter()
                .all(|s| *s == SubDeviceState::Op),
        );
        std::thread::sleep(o.cycle_time);
    }
    r.check(
        wrong == 0 && not_op == 0,
        format!(
            "{} cycles in OP: working counter {expected_wkc} expected, {wrong} differed; {not_op} found a SubDevice out of OP",
            o.cycles
        ),
    );
    // One line for scripts: what a replay of the captured LRW datagrams must reproduce.
    println!(
        "op: subdevices {} inputs {inputs} outputs {outputs} chunk {PDU_PAYLOAD} expected_wkc {expected_wkc}",
        group.len()
    );
    // The group is dropped here: ethercrab sends nothing on drop, so the line stays in OP.
    Ok(())
}

// The shapes of the control API's answers the page reads (docs/MODULES.md "Control API",
// docs/WEB.md "Stream").
export interface RackInput { channel: number; value: number; unit: string; source: string; open?: boolean }
export interface RackOutput { channel: number; commanded: number; driven: number; wire: number; unit: string; wiring_fault?: string }
export interface RackModule {
  module: number; rim: number; slot: number; card: string; description: string;
  card_id: string; module_ident: string; inputs: RackInput[]; outputs: RackOutput[];
}
export interface RackRim {
  rim: number; state: string; comm_error: boolean; power_supply_fan: boolean;
  power_supply_rpm: number; slot_card_fan: boolean; slot_card_rpm: number; modules: number[];
}
export interface RackInfo {
  esm: string; outputs_valid: boolean; detect_modules_override: boolean;
  cpu_fan_rpm: number; cpu_temperature: number; rims: RackRim[]; modules: RackModule[];
}
export interface LiveRim { rim: number; state: string; comm_error: boolean; power_supply_rpm: number; slot_card_rpm: number; event_status: string }
export interface LiveModule { module: number; in: (number | null)[]; out: [number, number, number][] }
export interface LiveSlave {
  slave: number; position: number; rack: boolean; esm: string; outputs_valid: boolean; station_address: number;
  al_status: number; al_status_code: number; al_status_text: string;
  pd_watchdog_running: boolean; pd_watchdog_expiries: number; rx_errors: number; frames: number;
  vendor_id: string; product_code: string; revision: string;
  cpu_fan_rpm: number; cpu_temperature: number; F380: string; F390: string;
  device_event_status: string; diagnosis_messages: number; diagnosis_newest: number;
  rims: LiveRim[]; modules: LiveModule[];
}
// GET /api/slaves: a rack (modules) or another device of the line (device: its description).
export interface SlaveEntry { slave: number; modules?: number; device?: string }
export interface LiveFrame { seq: number; t: number; slaves: LiveSlave[] }

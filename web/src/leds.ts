// The status LEDs a Fusion.IO rack lights, from the communication state of each RIM
// (programmer's guide §4.3 "Communication States").
export type LedColor = "green" | "amber" | "off";
export type RimState = "online" | "connected" | "offline" | "error";

export interface RimLeds {
  rimPort: LedColor; // the RIM device's RIM PORT LED
  rimPower: LedColor; // the RIM device's Power LED
  cmPort: LedColor; // the Fusion device's RIM Port RJ45 LED for this RIM
}

// §4.3: Online = RIM PORT green, Power green, the Fusion device's port green. Connected (did
// not authenticate, or shut itself down for a diagnostic, communication or unsafe wiring
// error; rackcat's "error" state is that shut-down) = RIM PORT amber, Power off, the Fusion
// device's port amber while the cable is in. Offline (cable pulled or power removed) = all off.
export function rimLeds(state: string): RimLeds {
  switch (state) {
    case "online":
      return { rimPort: "green", rimPower: "green", cmPort: "green" };
    case "connected":
    case "error":
      return { rimPort: "amber", rimPower: "off", cmPort: "amber" };
    default:
      return { rimPort: "off", rimPower: "off", cmPort: "off" };
  }
}

// §4.3: the Fusion device's Online LED is green when no safety, diagnostic or configuration
// issue is present: no active exception (0xF380 summary 0) and every RIM online.
export function fusionOnlineLed(activeSummary: number, rimStates: string[]): LedColor {
  return activeSummary === 0 && rimStates.every((s) => s === "online") ? "green" : "off";
}

// Reads an LCM event log with the lcm.jar reader and decodes every
// PLSA_STATE event with the generated Java type, as lcm-spy does with
// plsa_lcmtypes.jar on its class path. Prints one line per state:
// "utime seq bend_deg steer_deg", then "states N".
import java.io.ByteArrayInputStream;
import java.io.DataInputStream;
import java.io.IOException;

import lcm.logging.Log;
import plsa_lcm.actuator_state_t;

public class DecodePlsaLog {
  public static void main(String[] args) throws IOException {
    if (args.length != 1) {
      System.err.println("usage: DecodePlsaLog run.lcmlog");
      System.exit(2);
    }
    Log log = new Log(args[0], "r");
    int states = 0;
    while (true) {
      Log.Event e;
      try {
        e = log.readNext();
      } catch (java.io.EOFException end) {
        break;
      }
      if (!e.channel.equals("PLSA_STATE")) continue;
      actuator_state_t s = new actuator_state_t(new DataInputStream(new ByteArrayInputStream(e.data)));
      System.out.println(s.utime + " " + s.seq + " " + s.bend_deg + " " + s.steer_deg);
      ++states;
    }
    log.close();
    System.out.println("states " + states);
  }
}

// DecodeAll LOG [--prefix P] [CHANNEL=CLASS[:MIN]]...
//
// Reads an LCM event log with lcm.logging.Log and decodes every event of
// every channel starting with P (default "rtfuse/") the way lcm-spy does:
// the first 8 bytes are the type fingerprint, lcm.spy.LCMTypeDatabase (the
// class lcm-spy itself uses, which scans CLASSPATH and java.class.path for
// classes with an LCM_FINGERPRINT field) names the class, and the class's
// DataInput constructor decodes the bytes. On top of what lcm-spy checks,
// every message must be consumed exactly and re-encode to the same bytes.
//
// Each CHANNEL=CLASS[:MIN] argument is an expected channel: it must appear
// (at least MIN times, default 1) and decode as CLASS.
//
// Prints one line per channel and exits 1 on any missing channel, unknown
// fingerprint, wrong class or decode error; 2 on bad usage or an unreadable log.
import java.io.ByteArrayOutputStream;
import java.io.DataInput;
import java.io.EOFException;
import java.io.PrintStream;
import java.lang.reflect.Constructor;
import java.lang.reflect.InvocationTargetException;
import java.util.Arrays;
import java.util.Map;
import java.util.TreeMap;

import lcm.lcm.LCMDataInputStream;
import lcm.lcm.LCMDataOutputStream;
import lcm.lcm.LCMEncodable;
import lcm.logging.Log;
import lcm.spy.LCMTypeDatabase;

public class DecodeAll {
  static final class Channel {
    long events;
    long decoded;
    long bytes;
    String className;  // as decoded (first event)
    String expectedClass;
    long expectedMin = 0;
  }

  static final int MAX_ERRORS_PRINTED = 20;
  static int errors = 0;

  static void error(String msg) {
    if (errors < MAX_ERRORS_PRINTED) System.out.println("ERROR: " + msg);
    ++errors;
  }

  public static void main(String[] args) {
    String path = null;
    String prefix = "rtfuse/";
    Map<String, Channel> channels = new TreeMap<>();
    for (int i = 0; i < args.length; ++i) {
      String a = args[i];
      if (a.equals("--prefix") && i + 1 < args.length) {
        prefix = args[++i];
      } else if (a.contains("=")) {
        String ch = a.substring(0, a.indexOf('='));
        String rest = a.substring(a.indexOf('=') + 1);
        Channel c = new Channel();
        c.expectedMin = 1;
        int colon = rest.lastIndexOf(':');
        if (colon >= 0) {
          c.expectedMin = Long.parseLong(rest.substring(colon + 1));
          rest = rest.substring(0, colon);
        }
        c.expectedClass = rest;
        channels.put(ch, c);
      } else if (path == null) {
        path = a;
      } else {
        System.err.println("usage: DecodeAll LOG [--prefix P] [CHANNEL=CLASS[:MIN]]...");
        System.exit(2);
      }
    }
    if (path == null) {
      System.err.println("usage: DecodeAll LOG [--prefix P] [CHANNEL=CLASS[:MIN]]...");
      System.exit(2);
    }

    // What lcm-spy does at start-up: index every LCM type on the class path.
    LCMTypeDatabase types = indexTypes();

    long total = 0;
    long skipped = 0;
    try {
      Log log = new Log(path, "r");
      while (true) {
        Log.Event ev;
        try {
          ev = log.readNext();
        } catch (EOFException eof) {
          break;
        }
        ++total;
        if (!ev.channel.startsWith(prefix)) {
          ++skipped;
          continue;
        }
        Channel c = channels.computeIfAbsent(ev.channel, k -> new Channel());
        ++c.events;
        c.bytes += ev.data.length;
        decode(types, ev, c);
      }
      log.close();
    } catch (Exception e) {
      System.out.println("ERROR: cannot read log " + path + ": " + e);
      System.exit(2);
    }

    System.out.printf("%-24s %8s %8s  %s%n", "channel", "events", "decoded", "class");
    for (Map.Entry<String, Channel> e : channels.entrySet()) {
      Channel c = e.getValue();
      System.out.printf("%-24s %8d %8d  %s%n", e.getKey(), c.events, c.decoded,
                        c.className != null ? c.className : "-");
      if (c.expectedClass != null && c.events < c.expectedMin) {
        error(e.getKey() + ": " + c.events + " events, expected at least " + c.expectedMin
              + (c.events == 0 ? " (channel missing)" : ""));
      }
    }
    System.out.println(total + " events in the log, " + skipped + " on channels outside " + prefix);
    if (errors > 0) {
      System.out.println("FAIL: " + errors + " error(s)");
      System.exit(1);
    }
    System.out.println("OK: every " + prefix + "* event decoded as lcm-spy would");
  }

  // new LCMTypeDatabase(), with its class-path scan's chatter filtered: it
  // loads every class of lcm.jar, and lcm-spy's chart classes need jchart2d.jar,
  // which decoding does not (lcm-spy prints the same NoClassDefFoundErrors).
  static LCMTypeDatabase indexTypes() {
    PrintStream out = System.out;
    PrintStream err = System.err;
    ByteArrayOutputStream chatter = new ByteArrayOutputStream();
    PrintStream capture = new PrintStream(chatter, true);
    LCMTypeDatabase types;
    try {
      System.setOut(capture);
      System.setErr(capture);
      types = new LCMTypeDatabase();
    } finally {
      System.setOut(out);
      System.setErr(err);
    }
    int chartErrors = 0;
    for (String line : chatter.toString().split("\n")) {
      if (line.contains("info/monitorenter")) {
        ++chartErrors;
      } else if (!line.isEmpty() && !line.startsWith(" ")) {
        System.out.println(line);
      }
    }
    if (chartErrors > 0) {
      System.out.println("(" + chartErrors + " lcm-spy chart classes not loadable without jchart2d.jar: not needed to decode)");
    }
    return types;
  }

  static void decode(LCMTypeDatabase types, Log.Event ev, Channel c) {
    final String where = ev.channel + " event " + ev.eventNumber;
    if (ev.data.length < 8) {
      error(where + ": " + ev.data.length + " bytes, shorter than a fingerprint");
      return;
    }
    long fingerprint;
    try {
      fingerprint = new LCMDataInputStream(ev.data).readLong();
    } catch (Exception e) {
      error(where + ": " + e);
      return;
    }
    Class<?> cls = types.getClassByFingerprint(fingerprint);
    if (cls == null) {
      error(where + ": no LCM type on the class path has fingerprint "
            + String.format("0x%016x", fingerprint) + " (lcm-spy would show it undecoded)");
      return;
    }
    if (c.className == null) c.className = cls.getName();
    if (c.expectedClass != null && !cls.getName().equals(c.expectedClass)) {
      error(where + ": decodes as " + cls.getName() + ", expected " + c.expectedClass);
      return;
    }
    try {
      LCMDataInputStream in = new LCMDataInputStream(ev.data);
      Constructor<?> ctor = cls.getConstructor(DataInput.class);
      Object msg = ctor.newInstance(in);
      if (in.available() != 0) {
        error(where + ": " + in.available() + " bytes left over after decoding " + cls.getName());
        return;
      }
      LCMDataOutputStream out = new LCMDataOutputStream();
      ((LCMEncodable) msg).encode(out);
      if (!Arrays.equals(out.toByteArray(), ev.data)) {
        error(where + ": re-encoding " + cls.getName() + " does not give the logged bytes back");
        return;
      }
      ++c.decoded;
    } catch (InvocationTargetException e) {
      error(where + ": " + cls.getName() + " cannot decode it: " + e.getCause());
    } catch (Exception e) {
      error(where + ": " + cls.getName() + ": " + e);
    }
  }
}

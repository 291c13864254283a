package SpindleBench "Lumped thermal network of a vertical machining centre's spindle system (thermal-error testbench)"
  // Parameter sources are cited next to each value (short keys, full list in docs/model.md):
  //   [VDI]  VDI Heat Atlas, 2nd ed. (2010): natural convection, material data.
  //   [SKF]  SKF Rolling Bearings catalogue (2018) and Palmgren (1959), "Ball and Roller
  //          Bearing Engineering": friction torque M0 = 1e-7 f0 (nu n)^(2/3) dm^3, M1 = f1 P1 dm.
  //   [HK]   Harris & Kotzalas (2007), "Rolling Bearing Analysis", f0/f1 factors.
  //   [BT]   Bossmanns & Tu (1999), "A thermal model for high speed motorized spindles",
  //          Int. J. Mach. Tools Manuf. 39: bearing/housing resistances, rotating convection.
  //   [KR]   Kreith (1968) / Becker (1963): rotating cylinder Nu = 0.133 Re^(2/3) Pr^(1/3).
  //   [HOL]  Holkup et al. (2010), "Thermo-mechanical model of spindles", CIRP Annals 59.
  //   [MAY]  Mayr et al. (2012), "Thermal issues in machine tools", CIRP Annals 61.
  //   [ISO]  ISO 3448 viscosity grades; ISO 1 reference temperature 20 degC.
//   [D341] ASTM D341 (Walther): log10(log10(nu + 0.7)) = A - B log10(T), from nu_40 and nu_100.
//   [ISO230] ISO 230-3: thermal tests with a test mandrel and a probe fixture on the table.
  //   [EST]  engineering estimate for a VMC-850 class machine (masses from similar designs).
  //   [ST]   Stein & Tu (1994), thermally induced preload in spindle bearings, ASME J. Dyn. Syst.
  //          Meas. Control 116; [LS] Li & Shin (2004), ASME J. Manuf. Sci. Eng. 126 (issue 20).
  //   [LB]   Le & Bui (2023), grease versus air-oil lubrication of CNC spindle bearings, ETASR 13(5).

  package HeatTransfer "Thermal components named and connected like Modelica.Thermal.HeatTransfer"

    package Interfaces "Connectors and partial models"

      connector HeatPort "Thermal port for 1-dim. heat transfer"
        Real T(unit = "K") "Port temperature";
        flow Real Q_flow(unit = "W") "Heat flow rate (positive if flowing from outside into the component)";
      end HeatPort;

      connector HeatPort_a "Thermal port for 1-dim. heat transfer (the filled-square port of a component or assembly)"
        extends HeatPort;
      end HeatPort_a;

      connector HeatPort_b "Thermal port for 1-dim. heat transfer (the open-square port of a component or assembly)"
        extends HeatPort;
      end HeatPort_b;

      partial model Element1D "Partial heat transfer element with two HeatPorts that does not store energy"
        HeatPort port_a "Heat port a";
        HeatPort port_b "Heat port b";
        Real Q_flow(unit = "W") "Heat flow rate from port_a to port_b";
        Real dT(unit = "K") "port_a.T - port_b.T";
      equation
        dT = port_a.T - port_b.T;
        port_a.Q_flow = Q_flow;
        port_b.Q_flow = -Q_flow;
      end Element1D;

    end Interfaces;

    package Components "Lumped thermal components"

      model HeatCapacitor "Lumped thermal element storing heat"
        parameter Real C(unit = "J/K", min = 1.0e-3, max = 1.0e9) = 1000.0 "Heat capacity of element (= cp*m)";
        Real T(unit = "K", start = 293.15, fixed = true) "Temperature of element";
        Real der_T(unit = "K/s") "Time derivative of temperature (= der(T))";
        Interfaces.HeatPort port "Heat port of the element";
      equation
        T = port.T;
        der_T = der(T);
        C * der(T) = port.Q_flow;
      end HeatCapacitor;

      model ThermalConductor "Lumped thermal element transporting heat without storing it"
        extends Interfaces.Element1D;
        parameter Real G(unit = "W/K", min = 0.0, max = 1.0e5) = 1.0 "Constant thermal conductance of material";
      equation
        Q_flow = G * dT;
      end ThermalConductor;

      model Convection "Lumped thermal element for heat convection (Q_flow = Gc*dT)"
        input Real Gc(unit = "W/K") "Signal representing the convective thermal conductance";
        Real Q_flow(unit = "W") "Heat flow rate from solid to fluid";
        Real dT(unit = "K") "solid.T - fluid.T";
        Interfaces.HeatPort solid "Solid surface";
        Interfaces.HeatPort fluid "Fluid (air or coolant)";
      equation
        dT = solid.T - fluid.T;
        solid.Q_flow = Q_flow;
        fluid.Q_flow = -Q_flow;
        Q_flow = Gc * dT;
      end Convection;

      model SegmentedSolid "Solid body discretised into n finite-volume segments along one axis"
        // Segment i spans [(i-1)/n, i/n] of the axis (x = 0 at port_a, x = 1 at port_b). The
        // positional ports port_1..port_3 sit at fractions x1..x3: their heat is shared between
        // the two nearest segment centres and their temperature is interpolated linearly, so a
        // connection keeps its physical position when n changes (coarse and fine builds agree).
        parameter Integer n(min = 1, max = 50) = 4 "Number of segments (structural)";
        parameter Real C(unit = "J/K", min = 1.0e-3, max = 1.0e9) = 1.0e5 "Total heat capacity";
        parameter Real G(unit = "W/K", min = 1.0e-6, max = 1.0e5) = 1.0 "End-to-end axial conductance k*A/L";
        parameter Real L(unit = "m", min = 1.0e-3, max = 20.0) = 1.0 "Length along the axis";
        parameter Real alpha(unit = "1/K", min = 0.0, max = 1.0e-4) = 1.05e-5 "Linear thermal expansion coefficient";
        parameter Real T_nominal(unit = "K", min = 250.0, max = 330.0) = 293.15 "Temperature at which the body has its nominal length";
        parameter Real x1(unit = "1", min = 0.0, max = 1.0) = 0.5 "Position of port_1 as a fraction of L";
        parameter Real x2(unit = "1", min = 0.0, max = 1.0) = 0.5 "Position of port_2 as a fraction of L";
        parameter Real x3(unit = "1", min = 0.0, max = 1.0) = 0.5 "Position of port_3 as a fraction of L";
        parameter Real x_lo(unit = "1", min = 0.0, max = 1.0) = 0.0 "Start of the span whose elongation is reported in dL";
        parameter Real x_hi(unit = "1", min = 0.0, max = 1.0) = 1.0 "End of the span whose elongation is reported in dL";
        input Real G_side1(unit = "W/K") "Total conductance of the distributed surface side_1";
        input Real G_side2(unit = "W/K") "Total conductance of the distributed surface side_2";
        Real T[n](each unit = "K", each start = 293.15, each fixed = true) "Segment temperatures";
        Real Q_face[n + 1](each unit = "W") "Heat crossing face i into segment i (face 1: port_a, face n+1: port_b)";
        Real Q_side1[n](each unit = "W") "Heat from segment i through side_1";
        Real Q_side2[n](each unit = "W") "Heat from segment i through side_2";
        Real w1[n](each unit = "1") "Share of segment i in port_1";
        Real w2[n](each unit = "1") "Share of segment i in port_2";
        Real w3[n](each unit = "1") "Share of segment i in port_3";
        Real wT1[n](each unit = "K") "w1[i]*T[i]";
        Real wT2[n](each unit = "K") "w2[i]*T[i]";
        Real wT3[n](each unit = "K") "w3[i]*T[i]";
        Real Q_ports[n](each unit = "W") "Heat into segment i from port_1..port_3";
        Real dL_seg[n](each unit = "m") "Elongation of the part of segment i inside [x_lo, x_hi]";
        Real dL(unit = "m") "Elongation of the span [x_lo, x_hi] relative to T_nominal";
        Interfaces.HeatPort port_a "End face at x = 0";
        Interfaces.HeatPort port_b "End face at x = 1";
        Interfaces.HeatPort port_1 "Connection at x = x1";
        Interfaces.HeatPort port_2 "Connection at x = x2";
        Interfaces.HeatPort port_3 "Connection at x = x3";
        Interfaces.HeatPort side_1 "Distributed surface 1 (e.g. outer air), conductance G_side1";
        Interfaces.HeatPort side_2 "Distributed surface 2 (e.g. inner air, floor), conductance G_side2";
      equation
        for i in 1:n loop
          w1[i] = max(0.0, 1.0 - abs((i - 0.5) / n - min(max(x1, 0.5 / n), 1.0 - 0.5 / n)) * n);
          w2[i] = max(0.0, 1.0 - abs((i - 0.5) / n - min(max(x2, 0.5 / n), 1.0 - 0.5 / n)) * n);
          w3[i] = max(0.0, 1.0 - abs((i - 0.5) / n - min(max(x3, 0.5 / n), 1.0 - 0.5 / n)) * n);
          wT1[i] = w1[i] * T[i];
          wT2[i] = w2[i] * T[i];
          wT3[i] = w3[i] * T[i];
          Q_side1[i] = G_side1 / n * (T[i] - side_1.T);
          Q_side2[i] = G_side2 / n * (T[i] - side_2.T);
          Q_ports[i] = w1[i] * port_1.Q_flow + w2[i] * port_2.Q_flow + w3[i] * port_3.Q_flow;
          dL_seg[i] = alpha * L * max(0.0, min(i / n, x_hi) - max((i - 1) / n, x_lo)) * (T[i] - T_nominal);
        end for;
        Q_face[1] = port_a.Q_flow;
        for i in 2:n loop
          Q_face[i] = G * n * (T[i - 1] - T[i]);
        end for;
        Q_face[n + 1] = -port_b.Q_flow;
        for i in 1:n loop
          C / n * der(T[i]) = Q_face[i] - Q_face[i + 1] + Q_ports[i] - Q_side1[i] - Q_side2[i];
        end for;
        // the end ports sit on the end faces, half a segment from the first/last centre
        port_a.Q_flow = 2.0 * G * n * (port_a.T - T[1]);
        port_b.Q_flow = 2.0 * G * n * (port_b.T - T[n]);
        port_1.T = sum(wT1);
        port_2.T = sum(wT2);
        port_3.T = sum(wT3);
        side_1.Q_flow = -sum(Q_side1);
        side_2.Q_flow = -sum(Q_side2);
        dL = sum(dL_seg);
      end SegmentedSolid;

    end Components;

    package Sources "Thermal boundary conditions"

      model PrescribedTemperature "Variable temperature boundary condition in Kelvin"
        input Real T(unit = "K") "Prescribed temperature";
        Interfaces.HeatPort port "Boundary port";
      equation
        port.T = T;
      end PrescribedTemperature;

      model PrescribedHeatFlow "Prescribed heat flow boundary condition"
        input Real Q_flow(unit = "W") "Heat flow released into the connected component";
        Interfaces.HeatPort port "Port receiving the heat";
      equation
        port.Q_flow = -Q_flow;
      end PrescribedHeatFlow;

    end Sources;

    package Sensors "Thermal sensors"

      model TemperatureSensor "Absolute temperature sensor in Kelvin"
        output Real T(unit = "K") "Absolute temperature";
        Interfaces.HeatPort port "Measured port (draws no heat)";
      equation
        T = port.T;
        port.Q_flow = 0.0;
      end TemperatureSensor;

    end Sensors;

  end HeatTransfer;

  package Machine "Machine-specific heat sources, bodies and sensor models"

    model BearingFriction "Palmgren bearing friction heat with a Walther (ASTM D341) lubricant viscosity"
      // M0 = 1e-7 f0 z (nu n)^(2/3) dm^3 [N mm] for nu*n >= 2000 (else the constant 160e-7 f0 z dm^3),
      // M1 = f1 z P1 dm [N mm] with nu in mm2/s, n in rev/min, dm in mm [SKF, HK]; f0 is the factor
      // of ONE bearing, z the number of bearings in the set. The viscosity of the base oil at the
      // bearing temperature follows Walther's equation through nu_40 and nu_100 [D341].
      parameter Real f0(unit = "1", min = 0.0, max = 10.0) = 2.0 "Speed-dependent Palmgren factor of one bearing [HK]";
      parameter Real z(unit = "1", min = 1.0, max = 8.0) = 2.0 "Number of bearings in the set";
      parameter Real f1(unit = "1", min = 0.0, max = 1.0e-2) = 4.0e-4 "Load-dependent friction factor [HK]";
      parameter Real P1(unit = "N", min = 0.0, max = 1.0e5) = 1500.0 "Equivalent load of one bearing (mainly preload)";
      parameter Real dm(unit = "m", min = 1.0e-3, max = 1.0) = 0.09 "Bearing pitch diameter";
      parameter Real nu_40(unit = "mm2/s", min = 2.0, max = 1000.0) = 22.0 "Base-oil kinematic viscosity at 40 degC [ISO]";
      parameter Real nu_100(unit = "mm2/s", min = 1.0, max = 100.0) = 4.3 "Base-oil kinematic viscosity at 100 degC (below nu_40) [ISO]";
      input Real n_rpm(unit = "rev/min") "Shaft speed";
      input Real P_thermal(unit = "N") "Thermally induced preload added to P1 (inner ring and shaft hotter than outer ring and housing) [ST, BT]";
      Real walther_B(unit = "1") "Slope B of Walther's line (from nu_40 and nu_100)";
      Real walther_A(unit = "1") "Intercept A of Walther's line";
      Real nu(unit = "mm2/s") "Lubricant viscosity at the bearing temperature";
      Real M(unit = "N.m") "Friction torque of the set";
      Real Q_flow(unit = "W") "Friction heat released into the bearing region";
      HeatTransfer.Interfaces.HeatPort port "Bearing rings: receive the heat, set the viscosity";
    equation
      walther_B = (log(log(nu_40 + 0.7) / log(10.0)) - log(log(nu_100 + 0.7) / log(10.0))) / (log(373.15) - log(313.15)) "unit check: empirical: Walther [D341] on the numbers of nu in mm2/s and T in K";
      walther_A = log(log(nu_40 + 0.7) / log(10.0)) / log(10.0) + walther_B * log(313.15) / log(10.0) "unit check: empirical: Walther [D341] on the numbers of nu in mm2/s and T in K";
      nu = exp(log(10.0) * exp(log(10.0) * (walther_A - walther_B * log(port.T) / log(10.0)))) - 0.7 "unit check: empirical: Walther [D341] on the numbers of nu in mm2/s and T in K";
      M = z * (1.0e-10 * f0 * max(nu * abs(n_rpm), 2000.0) ^ (2.0 / 3.0) * (1000.0 * dm) ^ 3 + f1 * (P1 + P_thermal) * dm) "unit check: empirical: Palmgren [SKF] on the numbers of nu in mm2/s, n in rev/min, dm in mm, M0 in N mm";
      Q_flow = M * abs(n_rpm) * 2.0 * 3.14159265358979 / 60.0;
      port.Q_flow = -Q_flow;
    end BearingFriction;

    model ExpandingBody "Lumped body (one temperature) whose length L grows with its temperature"
      extends HeatTransfer.Components.HeatCapacitor;
      parameter Real L(unit = "m", min = 0.0, max = 5.0) = 0.1 "Length along the loop direction";
      parameter Real alpha(unit = "1/K", min = 0.0, max = 1.0e-4) = 1.15e-5 "Linear thermal expansion coefficient";
      parameter Real T_nominal(unit = "K", min = 250.0, max = 330.0) = 293.15 "Temperature at which the body has its nominal length";
      Real dL(unit = "m") "Elongation relative to T_nominal";
    equation
      dL = alpha * L * (T - T_nominal);
    end ExpandingBody;

    model ContactSensor "Surface temperature probe: small mass with contact and environment conductances"
      // A real probe is not the part: it has its own heat capacity (lag), a finite contact
      // conductance to the part and a loss to its surroundings, so it reads between the two.
      parameter Real C(unit = "J/K", min = 1.0e-3, max = 1.0e4) = 10.0 "Heat capacity of the probe with its mount [EST]";
      parameter Real G_contact(unit = "W/K", min = 1.0e-6, max = 1.0e3) = 0.5 "Conductance probe-part (contact resistance)";
      parameter Real G_env(unit = "W/K", min = 0.0, max = 1.0e3) = 0.02 "Conductance probe-surroundings";
      output Real T(unit = "K") "Probe reading";
      HeatTransfer.Components.HeatCapacitor body(C = C) "Probe body";
      HeatTransfer.Components.ThermalConductor contact(G = G_contact) "Contact to the measured part";
      HeatTransfer.Components.ThermalConductor env(G = G_env) "Loss to air or neighbouring part";
      HeatTransfer.Sensors.TemperatureSensor sensor "Ideal sensing element";
      HeatTransfer.Interfaces.HeatPort port "Measured part";
      HeatTransfer.Interfaces.HeatPort port_env "Surroundings (air or neighbouring part)";
    equation
      connect(port, contact.port_a);
      connect(contact.port_b, body.port);
      connect(body.port, env.port_a);
      connect(env.port_b, port_env);
      connect(body.port, sensor.port);
      T = sensor.T;
    end ContactSensor;

  end Machine;

  package Probes "Five-probe drift (ISO 230-3 / ISO 10791-10 set-up): cross-section temperature differences that bend the structure"

    model HalfSection "The '+' half of a part's cross-section: its mean temperature beside the part's mean"
      // A part of the network (column, headstock) has one temperature per segment: the mean over
      // its cross-section. Cut the section into a '+' half and a '-' half along one direction
      // (front/back or left/right) and the temperature field has a second mode, the difference
      // between the halves. This component is the '+' half's heat balance,
      //   (C/2) dT/dt = Q_in - 2 G_across (T - T_mean),
      // with the '-' half implied as 2 T_mean - T, so delta_T = 2 (T - T_mean). Q_in (set by
      // the assembly) is the '+' half's share of the heat into the part plus its own exchange
      // with the air. The part's mean is not changed by this mode (one-way coupling: the
      // neglected back-action is the difference of the two halves' air conductances times
      // delta_T / 2). A uniform difference delta_T between the half-centroids, depth/2 apart,
      // bends the part with the curvature alpha delta_T / (depth/2), the '+' side growing longer.
      parameter Real C(unit = "J/K", min = 1.0e-3, max = 1.0e9) = 1.0e5 "Heat capacity of the whole part (both halves)";
      parameter Real G_across(unit = "W/K", min = 1.0e-6, max = 1.0e5) = 10.0 "Conductance between the two half-centroids across the section";
      parameter Real depth(unit = "m", min = 1.0e-3, max = 10.0) = 0.5 "Size of the section in the direction of the cut (outer face to outer face)";
      parameter Real alpha(unit = "1/K", min = 0.0, max = 1.0e-4) = 1.05e-5 "Linear thermal expansion coefficient";
      input Real Q_in(unit = "W") "Heat into the '+' half: its share of the part's heat input and its own surface exchange";
      input Real T_mean(unit = "K") "Mean temperature of the part's section (the network's node)";
      Real T(unit = "K", start = 293.15, fixed = true) "Mean temperature of the '+' half";
      Real delta_T(unit = "K") "Temperature difference '+' half minus '-' half";
      Real curvature(unit = "1/m") "Bending curvature from delta_T, positive when the '+' side grows longer";
    equation
      C / 2.0 * der(T) = Q_in - 2.0 * G_across * (T - T_mean);
      delta_T = 2.0 * (T - T_mean);
      curvature = alpha * delta_T / (depth / 2.0);
    end HalfSection;

  end Probes;

  package Assemblies "Sub-assemblies of the machining centre, each with its own heat ports"
    // Each class is used once, by MachiningCentre, and keeps its components' machine-wide names
    // (front_bearing, x_nut, ...): the FMU names drop the assembly level, so
    // spindle_unit.front_bearing.C is the FMU parameter front_bearing_C as before the split
    // (spindlebench.model.equations.flat_name). An assembly declares the machine parameters it
    // uses, with their units and bounds but without values: the values have one home, the
    // machine, which passes them down. The local copy of a machine parameter p is called p_,
    // because pymoca 0.12 resolves the right-hand side of a modifier p = p inside the modified
    // component (a self-reference). Ports: HeatPort_a where the assembly's own node is exposed
    // (sensors, joints attach to it), HeatPort_b where it reaches a neighbour's node or the air.

    model SpindleUnit "Spindle unit: shaft, front and rear bearing sets with their friction, front cap, drawbar cylinder and the taper that holds the tool"
      import SpindleBench.HeatTransfer.Components.HeatCapacitor;
      import SpindleBench.HeatTransfer.Components.ThermalConductor;
      import SpindleBench.HeatTransfer.Components.Convection;
      import SpindleBench.HeatTransfer.Components.SegmentedSolid;
      import SpindleBench.HeatTransfer.Sources.PrescribedHeatFlow;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_a;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_b;
      import SpindleBench.Machine.BearingFriction;
      import SpindleBench.Machine.ExpandingBody;
      parameter Integer nSeg_(min = 2, max = 50) "Segments per large part (structural: set by the machine)";
      parameter Real T_ref_(unit = "K", min = 250.0, max = 330.0) "Reference temperature of the nominal geometry (20 degC) [ISO]";
      parameter Real alpha_steel_(unit = "1/K", min = 0.0, max = 1.0e-4) "Expansion coefficient of spindle, tool and screw steel [VDI]";
      parameter Real h_nat_(unit = "W/(m2.K)", min = 0.0, max = 100.0) "Natural convection plus radiation, machine surfaces in still air [VDI]";
      parameter Real n_ref_(unit = "rev/min", min = 1.0, max = 30000.0) "Reference speed of the speed-dependent laws";
      parameter Real h_rot_ref_(unit = "W/(m2.K)", min = 0.0, max = 1000.0) "Forced convection on the rotating shaft at n_ref, Nu = 0.133 Re^(2/3) Pr^(1/3) [KR, BT]";
      parameter Real front_preload_N_per_K_(unit = "N/K", min = 0.0, max = 1.0e4) "Thermally induced preload of the front set per K of shaft (at the bearing) over housing seat [ST, LS]";
      parameter Real rear_preload_N_per_K_(unit = "N/K", min = 0.0, max = 1.0e4) "Thermally induced preload of the rear set per K of shaft over housing seat (sliding outer rings relieve the axial part) [ST, LS]";
      parameter Real G_bearing_air_ref_(unit = "W/K", min = 0.0, max = 1.0e3) "Front bearing rings - air at n_ref: sealing-air purge and the air the rotating cage pumps through the labyrinth (oil-air: the lubricating air) [BT, LB]";
      parameter Real k_bearing_air_(unit = "1", min = 0.0, max = 2.0) "Exponent of the bearing-air conductance in speed [EST]";
      parameter Real rotor_front_share_(unit = "1", min = 0.0, max = 1.0) "Share of the rotor heat entering the shaft at the front bearing's place, the rest at the rear's";
      parameter Real A_shaft_(unit = "m2", min = 0.0, max = 100.0) "Shaft surface in the cavity (d 70 mm x 0.35 m)";
      parameter Real A_nose_(unit = "m2", min = 0.0, max = 100.0) "Spindle nose face and flange surface in open air";
      input Real spindle_speed_rpm(unit = "rev/min", min = 0.0, max = 30000.0) "Spindle speed";
      input Real Q_rotor_W(unit = "W") "Built-in motor losses released in the rotor on the shaft";
      SegmentedSolid spindle_shaft(n = nSeg_, C = 8300.0, G = 0.27, L = 0.55, alpha = alpha_steel_, T_nominal = T_ref_,
        x1 = 0.22, x2 = 0.85, x3 = 0.08, x_lo = 0.0, x_hi = 0.22)
        "Spindle shaft, nose (x=0) to drawbar end (x=1): 18 kg steel, d 70/20 mm, k 42 W/(m.K); front bearing at x1, rear at x2";
      HeatCapacitor front_bearing(C = 1000.0) "Front bearing rings and balls: 2x7014 angular contact set (2.2 kg)";
      HeatCapacitor front_cap(C = 3700.0) "Front bearing cap, seat sleeve and labyrinth ring (8 kg steel)";
      HeatCapacitor rear_bearing(C = 920.0) "Rear bearing region: 7012 pair (2 kg)";
      HeatCapacitor drawbar_cylinder(C = 4600.0) "Drawbar (tool unclamping) cylinder with its base (10 kg)";
      BearingFriction front_bearing_friction(f0 = 0.75, z = 2.0, f1 = 4.0e-4, P1 = 1500.0, dm = 0.09, nu_40 = 22.0, nu_100 = 4.3)
        "Front bearings 7014 set (2 single-row angular contact), grease with ISO VG 22 base oil; f0 per bearing tuned to 0.75 (handbook 2, run-in spindle bearings lower) [SKF, HK, D341]";
      BearingFriction rear_bearing_friction(f0 = 1.0, z = 2.0, f1 = 4.0e-4, P1 = 600.0, dm = 0.0775, nu_40 = 22.0, nu_100 = 4.3)
        "Rear bearings 7012 pair (2 single-row angular contact) [SKF, HK, D341]";
      ThermalConductor fb_housing(G = 15.0) "Front bearing outer rings - housing seat [BT, HOL]";
      ThermalConductor fb_shaft(G = 6.0) "Front bearing inner rings - shaft [BT, HOL]";
      ThermalConductor fb_cap(G = 4.0) "Front bearing outer ring face - clamping cap and seat sleeve [BT]";
      ThermalConductor cap_housing(G = 10.0) "Front bearing cap flange - housing front face (bolted)";
      ThermalConductor cap_air(G = 0.8) "Front bearing cap and labyrinth - air";
      ThermalConductor rb_housing(G = 8.0) "Rear bearing outer rings - housing seat [BT]";
      ThermalConductor rb_shaft(G = 3.0) "Rear bearing inner rings - shaft [BT]";
      ThermalConductor tool_taper(G = 4.0) "Spindle taper and face - tool holder (BT40 contact) [EST]";
      ThermalConductor drawbar_shaft(G = 0.4) "Drawbar cylinder - shaft end (rotary union)";
      ThermalConductor drawbar_housing(G = 1.5) "Drawbar cylinder base - housing top";
      ThermalConductor drawbar_air(G = 2.4) "Drawbar cylinder - air (0.3 m2)";
      Convection nose_convection "Spindle nose - air (speed dependent)";
      Convection bearing_air "Front bearing rings - air stream through the bearing (speed dependent)";
      PrescribedHeatFlow rotor_loss_front "Rotor losses entering the shaft at the front bearing's place";
      PrescribedHeatFlow rotor_loss_rear "Rotor losses entering the shaft at the rear bearing's place";
      HeatPort_b seat_front "Housing at the front bearing seat (outer rings and cap flange)";
      HeatPort_b seat_rear "Housing at the rear bearing seat";
      HeatPort_b housing_top "Housing top under the drawbar cylinder";
      HeatPort_b cavity "Headstock inner cavity around the shaft";
      HeatPort_b taper "Tool holder in the spindle taper";
      HeatPort_b air "Workshop air";
      HeatPort_a cap "Front bearing cap node (sensors, chiller jacket)";
      HeatPort_a drawbar "Drawbar cylinder node (sensor)";
    equation
      spindle_shaft.G_side1 = A_shaft_ * (h_nat_ + h_rot_ref_ * (abs(spindle_speed_rpm) / n_ref_) ^ (2.0 / 3.0));
      spindle_shaft.G_side2 = 0.0;
      nose_convection.Gc = A_nose_ * (h_nat_ + h_rot_ref_ * (abs(spindle_speed_rpm) / n_ref_) ^ (2.0 / 3.0));
      front_bearing_friction.n_rpm = spindle_speed_rpm;
      rear_bearing_friction.n_rpm = spindle_speed_rpm;
      connect(front_bearing_friction.port, front_bearing.port);
      connect(rear_bearing_friction.port, rear_bearing.port);
      connect(front_bearing.port, fb_housing.port_a);
      connect(fb_housing.port_b, seat_front);
      connect(front_bearing.port, fb_shaft.port_a);
      connect(fb_shaft.port_b, spindle_shaft.port_1);
      connect(front_bearing.port, fb_cap.port_a);
      connect(fb_cap.port_b, front_cap.port);
      connect(front_cap.port, cap_housing.port_a);
      connect(cap_housing.port_b, seat_front);
      connect(front_cap.port, cap_air.port_a);
      connect(cap_air.port_b, air);
      connect(front_cap.port, cap);
      connect(spindle_shaft.port_a, tool_taper.port_a);
      connect(tool_taper.port_b, taper);
      connect(rear_bearing.port, rb_housing.port_a);
      connect(rb_housing.port_b, seat_rear);
      connect(rear_bearing.port, rb_shaft.port_a);
      connect(rb_shaft.port_b, spindle_shaft.port_2);
      connect(spindle_shaft.side_1, cavity);
      connect(spindle_shaft.side_2, cavity);
      connect(spindle_shaft.port_3, nose_convection.solid);
      connect(nose_convection.fluid, air);
      connect(drawbar_cylinder.port, drawbar_shaft.port_a);
      connect(drawbar_shaft.port_b, spindle_shaft.port_b);
      connect(drawbar_cylinder.port, drawbar_housing.port_a);
      connect(drawbar_housing.port_b, housing_top);
      connect(drawbar_cylinder.port, drawbar_air.port_a);
      connect(drawbar_air.port_b, air);
      connect(drawbar_cylinder.port, drawbar);
      // thermally induced preload: the inner ring and shaft grow radially more than the outer ring
      // and housing while they are hotter, which loads the balls; it relaxes as the housing catches up
      front_bearing_friction.P_thermal = front_preload_N_per_K_ * max(0.0, spindle_shaft.port_1.T - seat_front.T);
      rear_bearing_friction.P_thermal = rear_preload_N_per_K_ * max(0.0, spindle_shaft.port_2.T - seat_rear.T);
      bearing_air.Gc = G_bearing_air_ref_ * (abs(spindle_speed_rpm) / n_ref_) ^ k_bearing_air_;
      connect(front_bearing.port, bearing_air.solid);
      connect(bearing_air.fluid, air);
      // rotor losses into the shaft between the bearings (shared between their two places)
      rotor_loss_front.Q_flow = rotor_front_share_ * Q_rotor_W;
      rotor_loss_rear.Q_flow = (1.0 - rotor_front_share_) * Q_rotor_W;
      connect(rotor_loss_front.port, spindle_shaft.port_1);
      connect(rotor_loss_rear.port, spindle_shaft.port_2);
    end SpindleUnit;

    model Headstock "Headstock: housing with its inner cavity, the belt-drive spindle motor on top and the spindle cooling unit at the front bearing seat"
      import SpindleBench.HeatTransfer.Components.HeatCapacitor;
      import SpindleBench.HeatTransfer.Components.ThermalConductor;
      import SpindleBench.HeatTransfer.Components.Convection;
      import SpindleBench.HeatTransfer.Components.SegmentedSolid;
      import SpindleBench.HeatTransfer.Sources.PrescribedHeatFlow;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_a;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_b;
      import SpindleBench.Machine.BearingFriction;
      import SpindleBench.Machine.ExpandingBody;
      parameter Integer nSeg_(min = 2, max = 50) "Segments per large part (structural: set by the machine)";
      parameter Real T_ref_(unit = "K", min = 250.0, max = 330.0) "Reference temperature of the nominal geometry (20 degC) [ISO]";
      parameter Real alpha_iron_(unit = "1/K", min = 0.0, max = 1.0e-4) "Expansion coefficient of grey cast iron EN-GJL-250 [VDI]";
      parameter Real h_nat_(unit = "W/(m2.K)", min = 0.0, max = 100.0) "Natural convection plus radiation, machine surfaces in still air [VDI]";
      parameter Real n_ref_(unit = "rev/min", min = 1.0, max = 30000.0) "Reference speed of the speed-dependent laws";
      parameter Real h_cavity_stir_(unit = "W/(m2.K)", min = 0.0, max = 1000.0) "Extra convection on cavity walls from air stirred at n_ref [EST]";
      parameter Real A_housing_out_(unit = "m2", min = 0.0, max = 100.0) "Outer surface of the headstock";
      parameter Real A_housing_in_(unit = "m2", min = 0.0, max = 100.0) "Inner surface of the headstock cavity";
      parameter Real P_spindle_motor_ref_(unit = "W", min = 0.0, max = 1.0e5) "Spindle motor no-load loss at n_ref (iron, friction, windage) [EST]";
      parameter Real k_spindle_motor_(unit = "1", min = 0.0, max = 4.0) "Exponent of the motor loss in speed [EST]";
      parameter Real rotor_loss_fraction_(unit = "1", min = 0.0, max = 1.0) "Share of the spindle motor losses released in the rotor on the shaft (0: separate belt-drive motor) [BT]";
      parameter Real cooling_enabled_(unit = "1", min = 0.0, max = 1.0) "1: cooling unit on, 0: off";
      parameter Real G_cooling_(unit = "W/K", min = 0.0, max = 1.0e4) "Conductance coolant jacket - front bearing seat [HOL]";
      input Real spindle_speed_rpm(unit = "rev/min", min = 0.0, max = 30000.0) "Spindle speed";
      SegmentedSolid housing(n = nSeg_, C = 161000.0, G = 1.6, L = 0.6, alpha = alpha_iron_, T_nominal = T_ref_,
        x1 = 0.4167, x2 = 0.8, x3 = 0.15, x_lo = 0.0, x_hi = 0.15)
        "Headstock housing, front bearing seat (x=0) to top (x=1): 350 kg cast iron; Z carriages at x1 (0.25 m above the seat), rear bearing seat at x2, Z nut bracket at x3";
      HeatCapacitor spindle_motor(C = 28800.0) "Spindle motor, 11 kW class, belt drive (60 kg)";
      HeatCapacitor inner_cavity(C = 3000.0) "Headstock inner cavity: air, belt, pulleys, fittings";
      PrescribedHeatFlow spindle_motor_loss "Spindle motor losses";
      ThermalConductor motor_housing(G = 2.0) "Spindle motor flange - headstock top";
      ThermalConductor motor_air(G = 12.0) "Spindle motor fan-cooled surface - air";
      ThermalConductor motor_column(G = 8.0) "Spindle motor bracket and fan exhaust air - column upper front";
      ThermalConductor cavity_air(G = 1.0) "Cavity - workshop air through openings";
      Convection cooling_bearing "Coolant jacket - front bearing seat";
      HeatPort_a seat_front "Front bearing seat (x = 0)";
      HeatPort_a seat_rear "Rear bearing seat";
      HeatPort_a top "Housing top (x = 1)";
      HeatPort_a carriages "Z guide carriages";
      HeatPort_a nut_bracket "Z nut bracket";
      HeatPort_a cavity "Inner cavity air";
      HeatPort_a motor "Spindle motor node";
      HeatPort_b column "Column upper front, behind the motor bracket and its fan exhaust";
      HeatPort_b air "Workshop air";
      HeatPort_b coolant "Coolant of the spindle cooling unit";
    equation
      housing.G_side1 = A_housing_out_ * h_nat_;
      housing.G_side2 = A_housing_in_ * (h_nat_ + h_cavity_stir_ * (abs(spindle_speed_rpm) / n_ref_) ^ (2.0 / 3.0));
      cooling_bearing.Gc = cooling_enabled_ * G_cooling_;
      spindle_motor_loss.Q_flow = (1.0 - rotor_loss_fraction_) * P_spindle_motor_ref_ * (abs(spindle_speed_rpm) / n_ref_) ^ k_spindle_motor_;
      connect(housing.port_a, seat_front);
      connect(housing.port_2, seat_rear);
      connect(housing.port_b, top);
      connect(housing.port_1, carriages);
      connect(housing.port_3, nut_bracket);
      connect(inner_cavity.port, cavity);
      connect(spindle_motor.port, motor);
      connect(spindle_motor_loss.port, spindle_motor.port);
      connect(spindle_motor.port, motor_housing.port_a);
      connect(motor_housing.port_b, housing.port_b);
      connect(spindle_motor.port, motor_air.port_a);
      connect(motor_air.port_b, air);
      connect(spindle_motor.port, motor_column.port_a);
      connect(motor_column.port_b, column);
      connect(housing.side_1, air);
      connect(housing.side_2, inner_cavity.port);
      connect(inner_cavity.port, cavity_air.port_a);
      connect(cavity_air.port_b, air);
      connect(coolant, cooling_bearing.fluid);
      connect(cooling_bearing.solid, housing.port_a);
    end Headstock;

    model Column "Column: the cast-iron upright from the bed to the Z screw's top bearing"
      import SpindleBench.HeatTransfer.Components.HeatCapacitor;
      import SpindleBench.HeatTransfer.Components.ThermalConductor;
      import SpindleBench.HeatTransfer.Components.Convection;
      import SpindleBench.HeatTransfer.Components.SegmentedSolid;
      import SpindleBench.HeatTransfer.Sources.PrescribedHeatFlow;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_a;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_b;
      import SpindleBench.Machine.BearingFriction;
      import SpindleBench.Machine.ExpandingBody;
      parameter Integer nSeg_(min = 2, max = 50) "Segments per large part (structural: set by the machine)";
      parameter Real T_ref_(unit = "K", min = 250.0, max = 330.0) "Reference temperature of the nominal geometry (20 degC) [ISO]";
      parameter Real alpha_iron_(unit = "1/K", min = 0.0, max = 1.0e-4) "Expansion coefficient of grey cast iron EN-GJL-250 [VDI]";
      parameter Real h_nat_(unit = "W/(m2.K)", min = 0.0, max = 100.0) "Natural convection plus radiation, machine surfaces in still air [VDI]";
      parameter Real A_column_(unit = "m2", min = 0.0, max = 100.0) "Column surface in air: the outer walls (the inner ribs of the box casting see little air movement) [EST]";
      SegmentedSolid column(n = nSeg_, C = 500000.0, G = 2.7, L = 1.42, alpha = alpha_iron_, T_nominal = T_ref_,
        x1 = 0.7, x2 = 0.5, x3 = 0.7, x_lo = 0.0, x_hi = 1.0)
        "Column, bed face (x=0) to the Z screw top bearing (x=1): 1090 kg cast iron; headstock carriages at x1, spindle motor bracket and exhaust air at x3 (beside the carriages)";
      HeatPort_a foot "Column foot on the bed (x = 0)";
      HeatPort_a carriages "Headstock carriages on the Z guides (x1)";
      HeatPort_a wall "Mid-height side wall: ambient probe mount, sunlit patch (x2)";
      HeatPort_a motor_bracket "Spindle motor bracket and exhaust air (x3)";
      HeatPort_a top "Z screw top bearing seat (x = 1)";
      HeatPort_b air "Workshop air";
    equation
      column.G_side1 = A_column_ * h_nat_;
      column.G_side2 = 0.0;
      connect(column.port_a, foot);
      connect(column.port_1, carriages);
      connect(column.port_2, wall);
      connect(column.port_3, motor_bracket);
      connect(column.port_b, top);
      connect(column.side_1, air);
      connect(column.side_2, air);
    end Column;

    model BedAndTable "Bed, and the saddle and table stacked on it through the Y guides"
      import SpindleBench.HeatTransfer.Components.HeatCapacitor;
      import SpindleBench.HeatTransfer.Components.ThermalConductor;
      import SpindleBench.HeatTransfer.Components.Convection;
      import SpindleBench.HeatTransfer.Components.SegmentedSolid;
      import SpindleBench.HeatTransfer.Sources.PrescribedHeatFlow;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_a;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_b;
      import SpindleBench.Machine.BearingFriction;
      import SpindleBench.Machine.ExpandingBody;
      parameter Integer nSeg_(min = 2, max = 50) "Segments per large part (structural: set by the machine)";
      parameter Real T_ref_(unit = "K", min = 250.0, max = 330.0) "Reference temperature of the nominal geometry (20 degC) [ISO]";
      parameter Real alpha_iron_(unit = "1/K", min = 0.0, max = 1.0e-4) "Expansion coefficient of grey cast iron EN-GJL-250 [VDI]";
      parameter Real h_nat_(unit = "W/(m2.K)", min = 0.0, max = 100.0) "Natural convection plus radiation, machine surfaces in still air [VDI]";
      parameter Real A_bed_(unit = "m2", min = 0.0, max = 100.0) "Bed surface in air";
      parameter Real A_table_(unit = "m2", min = 0.0, max = 100.0) "Table and saddle surface";
      parameter Real G_bed_floor_(unit = "W/K", min = 0.0, max = 1.0e4) "Bed underside - floor slab (levelling elements and grout)";
      SegmentedSolid bed(n = nSeg_, C = 1150000.0, G = 3.6, L = 2.0, alpha = alpha_iron_, T_nominal = T_ref_,
        x1 = 0.45, x2 = 0.1, x3 = 0.7, x_lo = 0.0, x_hi = 1.0)
        "Bed, front (x=0) to rear under the column (x=1): 2500 kg cast iron; saddle on the Y guides at x1";
      SegmentedSolid table(n = nSeg_, C = 414000.0, G = 32.0, L = 0.45, alpha = alpha_iron_, T_nominal = T_ref_,
        x1 = 0.5, x2 = 0.2, x3 = 0.8, x_lo = 0.0, x_hi = 1.0)
        "Saddle and table stacked vertically, saddle underside (x=0) to table top (x=1): 900 kg cast iron; X drive at x1, probe fixture on top";
      ThermalConductor bed_table(G = 15.0) "Bed - saddle through the Y guides";
      HeatPort_a column_foot "Bed rear under the column (x = 1)";
      HeatPort_a y_drive "Bed front: Y screw bearing seat (x = 0)";
      HeatPort_a saddle "Saddle underside: Y nut bracket (table x = 0)";
      HeatPort_a x_drive "Saddle at the X drive (table x1)";
      HeatPort_a top "Table top: probe fixture (table x = 1)";
      HeatPort_b floor "Floor slab under the bed";
      HeatPort_b air "Workshop air";
    equation
      bed.G_side1 = A_bed_ * h_nat_;
      bed.G_side2 = G_bed_floor_;
      table.G_side1 = A_table_ * h_nat_;
      table.G_side2 = 0.0;
      connect(bed.port_b, column_foot);
      connect(bed.port_a, y_drive);
      connect(bed.side_1, air);
      connect(bed.side_2, floor);
      connect(bed.port_1, bed_table.port_a);
      connect(bed_table.port_b, table.port_a);
      connect(table.port_a, saddle);
      connect(table.port_1, x_drive);
      connect(table.port_b, top);
      connect(table.side_1, air);
      connect(table.side_2, air);
    end BedAndTable;

    model TestSetup "ISO 230-3 measuring set-up: test mandrel in the spindle taper, probe fixture clamped on the table"
      import SpindleBench.HeatTransfer.Components.HeatCapacitor;
      import SpindleBench.HeatTransfer.Components.ThermalConductor;
      import SpindleBench.HeatTransfer.Components.Convection;
      import SpindleBench.HeatTransfer.Components.SegmentedSolid;
      import SpindleBench.HeatTransfer.Sources.PrescribedHeatFlow;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_a;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_b;
      import SpindleBench.Machine.BearingFriction;
      import SpindleBench.Machine.ExpandingBody;
      parameter Real T_ref_(unit = "K", min = 250.0, max = 330.0) "Reference temperature of the nominal geometry (20 degC) [ISO]";
      parameter Real alpha_steel_(unit = "1/K", min = 0.0, max = 1.0e-4) "Expansion coefficient of spindle, tool and screw steel [VDI]";
      parameter Real alpha_fixture_(unit = "1/K", min = 0.0, max = 1.0e-4) "Expansion coefficient of the probe fixture (steel; aluminium 2.3e-5) [VDI]";
      parameter Real h_nat_(unit = "W/(m2.K)", min = 0.0, max = 100.0) "Natural convection plus radiation, machine surfaces in still air [VDI]";
      parameter Real n_ref_(unit = "rev/min", min = 1.0, max = 30000.0) "Reference speed of the speed-dependent laws";
      parameter Real h_rot_ref_(unit = "W/(m2.K)", min = 0.0, max = 1000.0) "Forced convection on the rotating shaft at n_ref, Nu = 0.133 Re^(2/3) Pr^(1/3) [KR, BT]";
      parameter Real A_tool_(unit = "m2", min = 0.0, max = 100.0) "Tool holder and test mandrel surface (d 40 mm x 0.2 m plus the BT40 flange)";
      parameter Real A_fixture_(unit = "m2", min = 0.0, max = 100.0) "Probe fixture surface in air";
      input Real spindle_speed_rpm(unit = "rev/min", min = 0.0, max = 30000.0) "Spindle speed";
      ExpandingBody tool(C = 1400.0, L = 0.2, alpha = alpha_steel_, T_nominal = T_ref_)
        "BT40 tool holder with test mandrel d 40 mm, gauge length 0.2 m from the spindle nose to the measured face (3 kg steel) [ISO230]";
      ExpandingBody fixture(C = 2300.0, L = 0.15, alpha = alpha_fixture_, T_nominal = T_ref_)
        "Probe fixture on the table: bracket holding the eddy-current probe 0.15 m above the table, pointing up at the mandrel face (5 kg) [ISO230]";
      ThermalConductor fixture_table(G = 0.6) "Probe fixture foot - table top (clamped, small contact)";
      Convection tool_convection "Tool holder and mandrel - air (speed dependent)";
      Convection fixture_convection "Probe fixture - air";
      HeatPort_a taper "Spindle taper holding the tool";
      HeatPort_b table_top "Table top under the fixture foot";
      HeatPort_b air "Workshop air";
    equation
      tool_convection.Gc = A_tool_ * (h_nat_ + h_rot_ref_ * (abs(spindle_speed_rpm) / n_ref_) ^ (2.0 / 3.0));
      fixture_convection.Gc = A_fixture_ * h_nat_;
      connect(taper, tool.port);
      connect(tool.port, tool_convection.solid);
      connect(tool_convection.fluid, air);
      connect(table_top, fixture_table.port_a);
      connect(fixture_table.port_b, fixture.port);
      connect(fixture.port, fixture_convection.solid);
      connect(fixture_convection.fluid, air);
    end TestSetup;

    model FeedDriveZ "Z feed drive on the column: servo motor and top bearing on the column top, the screw down to the nut on the headstock (its growth is in the structural loop)"
      import SpindleBench.HeatTransfer.Components.HeatCapacitor;
      import SpindleBench.HeatTransfer.Components.ThermalConductor;
      import SpindleBench.HeatTransfer.Components.Convection;
      import SpindleBench.HeatTransfer.Components.SegmentedSolid;
      import SpindleBench.HeatTransfer.Sources.PrescribedHeatFlow;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_a;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_b;
      import SpindleBench.Machine.BearingFriction;
      import SpindleBench.Machine.ExpandingBody;
      parameter Real c_z_nut_(unit = "W.min/mm", min = 0.0, max = 1.0) "Z ball-nut friction heat per feed rate [EST]";
      parameter Real c_z_bearing_(unit = "W.min/mm", min = 0.0, max = 1.0) "Z screw top bearings heat per feed rate [EST]";
      parameter Real P_z_motor_idle_(unit = "W", min = 0.0, max = 1.0e4) "Z servo motor loss at standstill: holds the counterbalanced headstock [EST]";
      parameter Real c_z_motor_(unit = "W.min/mm", min = 0.0, max = 1.0) "Z servo motor loss per feed rate (lifts the headstock) [EST]";
      parameter Real T_ref_(unit = "K", min = 250.0, max = 330.0) "Reference temperature of the nominal geometry (20 degC) [ISO]";
      parameter Real alpha_steel_(unit = "1/K", min = 0.0, max = 1.0e-4) "Expansion coefficient of spindle, tool and screw steel [VDI]";
      input Real feed_mm_per_min(unit = "mm/min", min = 0.0, max = 60000.0) "Mean absolute feed rate of the axis";
      ExpandingBody z_screw(C = 1600.0, L = 0.35, alpha = alpha_steel_, T_nominal = T_ref_)
        "Z ball screw d 40 mm between its top bearing and the nut (3.5 kg steel)";
      HeatCapacitor z_nut(C = 1850.0) "Z ball-screw nut with bracket on the headstock (4 kg)";
      HeatCapacitor z_bearing_seat(C = 2300.0) "Z screw top bearing seat on the column (5 kg)";
      HeatCapacitor z_motor(C = 15000.0) "Z servo motor with flange housing on the column top (32 kg)";
      PrescribedHeatFlow z_nut_friction "Z nut friction";
      PrescribedHeatFlow z_bearing_friction "Z screw top bearing friction";
      PrescribedHeatFlow z_motor_loss "Z servo motor losses";
      ThermalConductor z_nut_housing(G = 0.5) "Z nut bracket - headstock";
      ThermalConductor z_nut_screw(G = 3.0) "Z nut - screw";
      ThermalConductor z_screw_seat(G = 1.0) "Z screw - top bearing seat";
      ThermalConductor z_seat_column(G = 3.0) "Z top bearing seat - column top";
      ThermalConductor z_motor_seat(G = 2.0) "Z motor flange - top bearing seat";
      ThermalConductor z_motor_air(G = 0.8) "Z motor - air (0.1 m2)";
      ThermalConductor z_nut_air(G = 0.3) "Z nut - air";
      ThermalConductor z_screw_air(G = 0.5) "Z screw - air";
      HeatPort_b carriage "Headstock at the Z nut bracket";
      HeatPort_b base "Column top at the top bearing seat";
      HeatPort_b air "Workshop air";
    equation
      z_nut_friction.Q_flow = c_z_nut_ * feed_mm_per_min;
      z_bearing_friction.Q_flow = c_z_bearing_ * feed_mm_per_min;
      z_motor_loss.Q_flow = P_z_motor_idle_ + c_z_motor_ * feed_mm_per_min;
      connect(z_nut_friction.port, z_nut.port);
      connect(z_bearing_friction.port, z_bearing_seat.port);
      connect(z_motor_loss.port, z_motor.port);
      connect(z_nut.port, z_nut_housing.port_a);
      connect(z_nut_housing.port_b, carriage);
      connect(z_nut.port, z_nut_screw.port_a);
      connect(z_nut_screw.port_b, z_screw.port);
      connect(z_screw.port, z_screw_seat.port_a);
      connect(z_screw_seat.port_b, z_bearing_seat.port);
      connect(z_bearing_seat.port, z_seat_column.port_a);
      connect(z_seat_column.port_b, base);
      connect(z_motor.port, z_motor_seat.port_a);
      connect(z_motor_seat.port_b, z_bearing_seat.port);
      connect(z_motor.port, z_motor_air.port_a);
      connect(z_motor_air.port_b, air);
      connect(z_nut.port, z_nut_air.port_a);
      connect(z_nut_air.port_b, air);
      connect(z_screw.port, z_screw_air.port_a);
      connect(z_screw_air.port_b, air);
    end FeedDriveZ;

    model FeedDriveX "X feed drive on the saddle: moves the table"
      import SpindleBench.HeatTransfer.Components.HeatCapacitor;
      import SpindleBench.HeatTransfer.Components.ThermalConductor;
      import SpindleBench.HeatTransfer.Components.Convection;
      import SpindleBench.HeatTransfer.Components.SegmentedSolid;
      import SpindleBench.HeatTransfer.Sources.PrescribedHeatFlow;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_a;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_b;
      import SpindleBench.Machine.BearingFriction;
      import SpindleBench.Machine.ExpandingBody;
      parameter Real c_x_nut_(unit = "W.min/mm", min = 0.0, max = 1.0) "X ball-nut friction heat per feed rate (0.43 N.m preload torque, 10 mm lead) [EST]";
      parameter Real c_x_bearing_(unit = "W.min/mm", min = 0.0, max = 1.0) "X screw support bearings heat per feed rate [EST]";
      parameter Real P_x_motor_idle_(unit = "W", min = 0.0, max = 1.0e4) "X servo motor loss at standstill (holding, position control) [EST]";
      parameter Real c_x_motor_(unit = "W.min/mm", min = 0.0, max = 1.0) "X servo motor loss per feed rate (reciprocating, acceleration currents) [EST]";
      input Real feed_mm_per_min(unit = "mm/min", min = 0.0, max = 60000.0) "Mean absolute feed rate of the axis";
      HeatCapacitor x_motor(C = 15000.0) "X servo motor with flange housing and mounting bracket (32 kg)";
      HeatCapacitor x_nut(C = 1850.0) "X ball-screw nut with bracket (4 kg)";
      HeatCapacitor x_screw(C = 4000.0) "X ball screw d 32 mm x 1 m with coupling (8 kg)";
      HeatCapacitor x_bearing_seat(C = 2300.0) "X screw support bearing seat (5 kg)";
      PrescribedHeatFlow x_nut_friction "X nut friction";
      PrescribedHeatFlow x_bearing_friction "X screw support bearing friction";
      PrescribedHeatFlow x_motor_loss "X servo motor losses";
      ThermalConductor x_nut_table(G = 1.5) "X nut bracket - table";
      ThermalConductor x_nut_screw(G = 3.0) "X nut - screw";
      ThermalConductor x_screw_seat(G = 1.0) "X screw - support bearing seat";
      ThermalConductor x_seat_table(G = 3.0) "X bearing seat - saddle";
      ThermalConductor x_motor_seat(G = 2.0) "X motor flange - bearing seat";
      ThermalConductor x_motor_air(G = 0.8) "X motor - air (0.1 m2)";
      ThermalConductor x_nut_air(G = 0.3) "X nut - air";
      ThermalConductor x_screw_air(G = 0.5) "X screw - air";
      HeatPort_b carriage "Table at the nut bracket";
      HeatPort_b base "Saddle at the support bearing seat";
      HeatPort_b air "Workshop air";
      HeatPort_a nut "Nut node (sensors)";
      HeatPort_a motor "Motor node (sensors)";
      HeatPort_a bearing_seat "Support bearing seat node (sensors)";
    equation
      x_nut_friction.Q_flow = c_x_nut_ * abs(feed_mm_per_min);
      x_bearing_friction.Q_flow = c_x_bearing_ * abs(feed_mm_per_min);
      x_motor_loss.Q_flow = P_x_motor_idle_ + c_x_motor_ * abs(feed_mm_per_min);
      connect(x_nut_friction.port, x_nut.port);
      connect(x_bearing_friction.port, x_bearing_seat.port);
      connect(x_motor_loss.port, x_motor.port);
      connect(x_nut.port, x_nut_table.port_a);
      connect(x_nut_table.port_b, carriage);
      connect(x_nut.port, x_nut_screw.port_a);
      connect(x_nut_screw.port_b, x_screw.port);
      connect(x_screw.port, x_screw_seat.port_a);
      connect(x_screw_seat.port_b, x_bearing_seat.port);
      connect(x_bearing_seat.port, x_seat_table.port_a);
      connect(x_seat_table.port_b, base);
      connect(x_motor.port, x_motor_seat.port_a);
      connect(x_motor_seat.port_b, x_bearing_seat.port);
      connect(x_motor.port, x_motor_air.port_a);
      connect(x_motor_air.port_b, air);
      connect(x_nut.port, x_nut_air.port_a);
      connect(x_nut_air.port_b, air);
      connect(x_screw.port, x_screw_air.port_a);
      connect(x_screw_air.port_b, air);
      connect(x_nut.port, nut);
      connect(x_motor.port, motor);
      connect(x_bearing_seat.port, bearing_seat);
    end FeedDriveX;

    model FeedDriveY "Y feed drive on the bed: moves the saddle"
      import SpindleBench.HeatTransfer.Components.HeatCapacitor;
      import SpindleBench.HeatTransfer.Components.ThermalConductor;
      import SpindleBench.HeatTransfer.Components.Convection;
      import SpindleBench.HeatTransfer.Components.SegmentedSolid;
      import SpindleBench.HeatTransfer.Sources.PrescribedHeatFlow;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_a;
      import SpindleBench.HeatTransfer.Interfaces.HeatPort_b;
      import SpindleBench.Machine.BearingFriction;
      import SpindleBench.Machine.ExpandingBody;
      parameter Real c_y_nut_(unit = "W.min/mm", min = 0.0, max = 1.0) "Y ball-nut friction heat per feed rate [EST]";
      parameter Real c_y_bearing_(unit = "W.min/mm", min = 0.0, max = 1.0) "Y screw support bearings heat per feed rate [EST]";
      parameter Real P_y_motor_idle_(unit = "W", min = 0.0, max = 1.0e4) "Y servo motor loss at standstill [EST]";
      parameter Real c_y_motor_(unit = "W.min/mm", min = 0.0, max = 1.0) "Y servo motor loss per feed rate (heavier axis) [EST]";
      input Real feed_mm_per_min(unit = "mm/min", min = 0.0, max = 60000.0) "Mean absolute feed rate of the axis";
      HeatCapacitor y_motor(C = 15000.0) "Y servo motor with flange housing and mounting bracket (32 kg)";
      HeatCapacitor y_nut(C = 1850.0) "Y ball-screw nut with bracket (4 kg)";
      HeatCapacitor y_screw(C = 4000.0) "Y ball screw d 32 mm x 1 m with coupling (8 kg)";
      HeatCapacitor y_bearing_seat(C = 2300.0) "Y screw support bearing seat (5 kg)";
      PrescribedHeatFlow y_nut_friction "Y nut friction";
      PrescribedHeatFlow y_bearing_friction "Y screw support bearing friction";
      PrescribedHeatFlow y_motor_loss "Y servo motor losses";
      ThermalConductor y_nut_table(G = 1.5) "Y nut bracket - saddle";
      ThermalConductor y_nut_screw(G = 3.0) "Y nut - screw";
      ThermalConductor y_screw_seat(G = 1.0) "Y screw - support bearing seat";
      ThermalConductor y_seat_bed(G = 3.0) "Y bearing seat - bed";
      ThermalConductor y_motor_seat(G = 2.0) "Y motor flange - bearing seat";
      ThermalConductor y_motor_air(G = 0.8) "Y motor - air (0.1 m2)";
      ThermalConductor y_nut_air(G = 0.3) "Y nut - air";
      ThermalConductor y_screw_air(G = 0.5) "Y screw - air";
      HeatPort_b carriage "Saddle at the nut bracket";
      HeatPort_b base "Bed front at the support bearing seat";
      HeatPort_b air "Workshop air";
      HeatPort_a nut "Nut node (sensors)";
      HeatPort_a motor "Motor node (sensors)";
      HeatPort_a bearing_seat "Support bearing seat node (sensors)";
    equation
      y_nut_friction.Q_flow = c_y_nut_ * abs(feed_mm_per_min);
      y_bearing_friction.Q_flow = c_y_bearing_ * abs(feed_mm_per_min);
      y_motor_loss.Q_flow = P_y_motor_idle_ + c_y_motor_ * abs(feed_mm_per_min);
      connect(y_nut_friction.port, y_nut.port);
      connect(y_bearing_friction.port, y_bearing_seat.port);
      connect(y_motor_loss.port, y_motor.port);
      connect(y_nut.port, y_nut_table.port_a);
      connect(y_nut_table.port_b, carriage);
      connect(y_nut.port, y_nut_screw.port_a);
      connect(y_nut_screw.port_b, y_screw.port);
      connect(y_screw.port, y_screw_seat.port_a);
      connect(y_screw_seat.port_b, y_bearing_seat.port);
      connect(y_bearing_seat.port, y_seat_bed.port_a);
      connect(y_seat_bed.port_b, base);
      connect(y_motor.port, y_motor_seat.port_a);
      connect(y_motor_seat.port_b, y_bearing_seat.port);
      connect(y_motor.port, y_motor_air.port_a);
      connect(y_motor_air.port_b, air);
      connect(y_nut.port, y_nut_air.port_a);
      connect(y_nut_air.port_b, air);
      connect(y_screw.port, y_screw_air.port_a);
      connect(y_screw_air.port_b, air);
      connect(y_nut.port, nut);
      connect(y_motor.port, motor);
      connect(y_bearing_seat.port, bearing_seat);
    end FeedDriveY;

  end Assemblies;

  model MachiningCentre "Vertical machining centre: spindle, tool, headstock, Z drive, column, bed, table, X/Y drives, probe fixture"
    import SpindleBench.HeatTransfer.Components.HeatCapacitor;
    import SpindleBench.HeatTransfer.Components.ThermalConductor;
    import SpindleBench.HeatTransfer.Components.Convection;
    import SpindleBench.HeatTransfer.Components.SegmentedSolid;
    import SpindleBench.HeatTransfer.Sources.PrescribedTemperature;
    import SpindleBench.HeatTransfer.Sources.PrescribedHeatFlow;
    import SpindleBench.Machine.BearingFriction;
    import SpindleBench.Machine.ExpandingBody;
    import SpindleBench.Machine.ContactSensor;
    import SpindleBench.Probes.HalfSection;
    import SpindleBench.Assemblies.*;

    // ---- structure and operating inputs --------------------------------------------------
    parameter Integer nSeg(min = 2, max = 50) = 12 "Segments per large part (structural: set at build time)";
    input Real spindle_speed_rpm(unit = "rev/min", min = 0.0, max = 30000.0, start = 0.0) "Spindle speed";
    input Real feed_x_mm_per_min(unit = "mm/min", min = 0.0, max = 60000.0, start = 0.0) "Mean absolute feed rate of the X axis";
    input Real feed_y_mm_per_min(unit = "mm/min", min = 0.0, max = 60000.0, start = 0.0) "Mean absolute feed rate of the Y axis";
    input Real ambient_C(unit = "degC", min = -50.0, max = 80.0, start = 20.0) "Ambient air temperature";

    // ---- global physical parameters -------------------------------------------------------
    parameter Real T_ref(unit = "K", min = 250.0, max = 330.0) = 293.15 "Reference temperature of the nominal geometry (20 degC) [ISO]";
    parameter Real T_start(unit = "K", min = 220.0, max = 360.0) = 293.15 "Start temperature of every node and probe whose start value the importer does not set";
    parameter Real alpha_iron(unit = "1/K", min = 0.0, max = 1.0e-4) = 1.05e-5 "Expansion coefficient of grey cast iron EN-GJL-250 [VDI]";
    parameter Real alpha_steel(unit = "1/K", min = 0.0, max = 1.0e-4) = 1.15e-5 "Expansion coefficient of spindle, tool and screw steel [VDI]";
    parameter Real alpha_fixture(unit = "1/K", min = 0.0, max = 1.0e-4) = 1.15e-5 "Expansion coefficient of the probe fixture (steel; aluminium 2.3e-5) [VDI]";
    parameter Real h_nat(unit = "W/(m2.K)", min = 0.0, max = 100.0) = 8.0 "Natural convection plus radiation, machine surfaces in still air [VDI]";
    parameter Real n_ref(unit = "rev/min", min = 1.0, max = 30000.0) = 4000.0 "Reference speed of the speed-dependent laws";
    parameter Real h_rot_ref(unit = "W/(m2.K)", min = 0.0, max = 1000.0) = 110.0 "Forced convection on the rotating shaft at n_ref, Nu = 0.133 Re^(2/3) Pr^(1/3) [KR, BT]";
    parameter Real h_cavity_stir(unit = "W/(m2.K)", min = 0.0, max = 1000.0) = 6.0 "Extra convection on cavity walls from air stirred at n_ref [EST]";

    // ---- spindle cooling unit (oil chiller around the front bearing seat) -----------------
    parameter Real cooling_enabled(unit = "1", min = 0.0, max = 1.0) = 0.0 "1: cooling unit on, 0: off";
    parameter Real cooling_follows_ambient(unit = "1", min = 0.0, max = 1.0) = 1.0 "1: coolant at ambient + setpoint, 0: at absolute setpoint";
    parameter Real cooling_setpoint_C(unit = "degC", min = -50.0, max = 80.0) = 0.0 "Coolant temperature (absolute) or offset from ambient (following)";
    parameter Real G_cooling(unit = "W/K", min = 0.0, max = 1.0e4) = 25.0 "Conductance coolant jacket - front bearing seat [HOL]";

    // ---- spindle-driven mechanisms (issue 20): a gain of 0 switches each off (docs/model.md) ----
    parameter Real front_preload_N_per_K(unit = "N/K", min = 0.0, max = 1.0e4) = 200.0 "Thermally induced preload of the front set per K of shaft (at the bearing) over housing seat [ST, LS]";
    parameter Real rear_preload_N_per_K(unit = "N/K", min = 0.0, max = 1.0e4) = 0.0 "Thermally induced preload of the rear set per K of shaft over housing seat (sliding outer rings relieve the axial part) [ST, LS]";
    parameter Real G_bearing_air_ref(unit = "W/K", min = 0.0, max = 1.0e3) = 2.0 "Front bearing rings - air at n_ref: sealing-air purge and the air the rotating cage pumps through the labyrinth (oil-air: the lubricating air) [BT, LB]";
    parameter Real k_bearing_air(unit = "1", min = 0.0, max = 2.0) = 0.8 "Exponent of the bearing-air conductance in speed [EST]";
    // built-in motor (motorized spindle): rotor on the shaft between the bearings, stator in the housing
    parameter Real rotor_loss_fraction(unit = "1", min = 0.0, max = 1.0) = 0.0 "Share of the spindle motor losses released in the rotor on the shaft (0: separate belt-drive motor) [BT]";
    parameter Real rotor_front_share(unit = "1", min = 0.0, max = 1.0) = 0.5 "Share of the rotor heat entering the shaft at the front bearing's place, the rest at the rear's";
    // chiller jacket around stator and front bearing seat, supply set-point following the room
    parameter Real jacket_enabled(unit = "1", min = 0.0, max = 1.0) = 0.0 "1: chiller jacket on, 0: no jacket";
    parameter Real jacket_offset_K(unit = "K", min = -20.0, max = 20.0) = 0.0 "Chiller supply temperature minus room air (set-point following the room) [MAY]";
    parameter Real G_jacket_stator(unit = "W/K", min = 0.0, max = 1.0e4) = 0.0 "Jacket coolant - stator sleeve (spiral groove jacket) [BT, HOL]";
    parameter Real G_jacket_front(unit = "W/K", min = 0.0, max = 1.0e4) = 0.0 "Jacket coolant - front bearing seat sleeve [HOL]";
    parameter Real jacket_flow_W_per_K(unit = "W/K", min = 1.0, max = 1.0e5) = 120.0 "Coolant capacity flow m_dot c_p (about 4 l/min of spindle oil)";

    // ---- heat sources -----------------------------------------------------------------
    parameter Real P_spindle_motor_ref(unit = "W", min = 0.0, max = 1.0e5) = 140.0 "Spindle motor no-load loss at n_ref (iron, friction, windage) [EST]";
    parameter Real k_spindle_motor(unit = "1", min = 0.0, max = 4.0) = 1.6 "Exponent of the motor loss in speed [EST]";
    parameter Real c_x_nut(unit = "W.min/mm", min = 0.0, max = 1.0) = 0.0045 "X ball-nut friction heat per feed rate (0.43 N.m preload torque, 10 mm lead) [EST]";
    parameter Real c_y_nut(unit = "W.min/mm", min = 0.0, max = 1.0) = 0.0045 "Y ball-nut friction heat per feed rate [EST]";
    parameter Real c_z_nut(unit = "W.min/mm", min = 0.0, max = 1.0) = 0.0045 "Z ball-nut friction heat per feed rate [EST]";
    parameter Real c_x_bearing(unit = "W.min/mm", min = 0.0, max = 1.0) = 0.003 "X screw support bearings heat per feed rate [EST]";
    parameter Real c_y_bearing(unit = "W.min/mm", min = 0.0, max = 1.0) = 0.003 "Y screw support bearings heat per feed rate [EST]";
    parameter Real c_z_bearing(unit = "W.min/mm", min = 0.0, max = 1.0) = 0.003 "Z screw top bearings heat per feed rate [EST]";
    parameter Real P_x_motor_idle(unit = "W", min = 0.0, max = 1.0e4) = 4.0 "X servo motor loss at standstill (holding, position control) [EST]";
    parameter Real P_y_motor_idle(unit = "W", min = 0.0, max = 1.0e4) = 4.0 "Y servo motor loss at standstill [EST]";
    parameter Real P_z_motor_idle(unit = "W", min = 0.0, max = 1.0e4) = 4.0 "Z servo motor loss at standstill: holds the counterbalanced headstock [EST]";
    parameter Real c_x_motor(unit = "W.min/mm", min = 0.0, max = 1.0) = 0.006 "X servo motor loss per feed rate (reciprocating, acceleration currents) [EST]";
    parameter Real c_y_motor(unit = "W.min/mm", min = 0.0, max = 1.0) = 0.007 "Y servo motor loss per feed rate (heavier axis) [EST]";
    parameter Real c_z_motor(unit = "W.min/mm", min = 0.0, max = 1.0) = 0.008 "Z servo motor loss per feed rate (lifts the headstock) [EST]";
    parameter Real feed_z_mm_per_min(unit = "mm/min", min = 0.0, max = 60000.0) = 0.0 "Mean absolute Z feed rate of a run (the paper's experiments keep Z still)";

    // ---- surfaces (m2) ----------------------------------------------------------------
    parameter Real A_shaft(unit = "m2", min = 0.0, max = 100.0) = 0.077 "Shaft surface in the cavity (d 70 mm x 0.35 m)";
    parameter Real A_nose(unit = "m2", min = 0.0, max = 100.0) = 0.012 "Spindle nose face and flange surface in open air";
    parameter Real A_tool(unit = "m2", min = 0.0, max = 100.0) = 0.04 "Tool holder and test mandrel surface (d 40 mm x 0.2 m plus the BT40 flange)";
    parameter Real A_housing_out(unit = "m2", min = 0.0, max = 100.0) = 1.6 "Outer surface of the headstock";
    parameter Real A_housing_in(unit = "m2", min = 0.0, max = 100.0) = 0.8 "Inner surface of the headstock cavity";
    parameter Real A_column(unit = "m2", min = 0.0, max = 100.0) = 4.5 "Column surface in air: the outer walls (the inner ribs of the box casting see little air movement) [EST]";
    parameter Real A_bed(unit = "m2", min = 0.0, max = 100.0) = 6.0 "Bed surface in air";
    parameter Real A_table(unit = "m2", min = 0.0, max = 100.0) = 3.0 "Table and saddle surface";
    parameter Real A_fixture(unit = "m2", min = 0.0, max = 100.0) = 0.12 "Probe fixture surface in air";
    parameter Real G_bed_floor(unit = "W/K", min = 0.0, max = 1.0e4) = 10.0 "Bed underside - floor slab (levelling elements and grout)";

    // ---- geometry of the structural loop ----------------------------------------------
    parameter Real H_bed(unit = "m", min = 0.0, max = 5.0) = 0.5 "Bed height (vertical growth under column and under table)";

    // ---- sub-assemblies, connected through their heat ports (below) ------------------------
    // The order of the declarations keeps the FMU's variable order (docs/contracts.md)
    SpindleUnit spindle_unit(nSeg_ = nSeg, T_ref_ = T_ref, alpha_steel_ = alpha_steel, h_nat_ = h_nat, n_ref_ = n_ref,
      h_rot_ref_ = h_rot_ref, front_preload_N_per_K_ = front_preload_N_per_K, rear_preload_N_per_K_ = rear_preload_N_per_K,
      G_bearing_air_ref_ = G_bearing_air_ref, k_bearing_air_ = k_bearing_air, rotor_front_share_ = rotor_front_share,
      A_shaft_ = A_shaft, A_nose_ = A_nose) "Spindle unit";
    Headstock headstock(nSeg_ = nSeg, T_ref_ = T_ref, alpha_iron_ = alpha_iron, h_nat_ = h_nat, n_ref_ = n_ref,
      h_cavity_stir_ = h_cavity_stir, A_housing_out_ = A_housing_out, A_housing_in_ = A_housing_in,
      P_spindle_motor_ref_ = P_spindle_motor_ref, k_spindle_motor_ = k_spindle_motor,
      rotor_loss_fraction_ = rotor_loss_fraction, cooling_enabled_ = cooling_enabled, G_cooling_ = G_cooling) "Headstock";
    Column column_unit(nSeg_ = nSeg, T_ref_ = T_ref, alpha_iron_ = alpha_iron, h_nat_ = h_nat, A_column_ = A_column) "Column";
    ThermalConductor headstock_column(G = 40.0) "Headstock - column through the four Z guide carriages and the rails";
    ThermalConductor column_bed(G = 20.0) "Column foot - bed (bolted joint)";
    BedAndTable bed_and_table(nSeg_ = nSeg, T_ref_ = T_ref, alpha_iron_ = alpha_iron, h_nat_ = h_nat, A_bed_ = A_bed,
      A_table_ = A_table, G_bed_floor_ = G_bed_floor) "Bed, saddle and table";
    ThermalConductor floor_air(G = 30.0) "Floor slab - workshop air";
    TestSetup test_setup(T_ref_ = T_ref, alpha_steel_ = alpha_steel, alpha_fixture_ = alpha_fixture, h_nat_ = h_nat,
      n_ref_ = n_ref, h_rot_ref_ = h_rot_ref, A_tool_ = A_tool, A_fixture_ = A_fixture) "Test mandrel and probe fixture";
    FeedDriveZ z_drive(c_z_nut_ = c_z_nut, c_z_bearing_ = c_z_bearing, P_z_motor_idle_ = P_z_motor_idle,
      c_z_motor_ = c_z_motor, T_ref_ = T_ref, alpha_steel_ = alpha_steel) "Z feed drive";
    FeedDriveX x_drive(c_x_nut_ = c_x_nut, c_x_bearing_ = c_x_bearing, P_x_motor_idle_ = P_x_motor_idle,
      c_x_motor_ = c_x_motor) "X feed drive";
    FeedDriveY y_drive(c_y_nut_ = c_y_nut, c_y_bearing_ = c_y_bearing, P_y_motor_idle_ = P_y_motor_idle,
      c_y_motor_ = c_y_motor) "Y feed drive";

    // ---- the machine's surroundings and the joints between the sub-assemblies -----------------

    HeatCapacitor floor_slab(C = 2.6e6) "Concrete floor under the machine (3 t), lags the air by about a day";

    // ---- boundaries and sources --------------------------------------------------------
    PrescribedTemperature ambient "Workshop air";
    PrescribedTemperature coolant "Coolant of the spindle cooling unit";

    // spindle-driven mechanisms and built-in motor (issue 20)
    ThermalConductor stator_housing(G = 0.0) "Stator sleeve - housing between the bearings (built-in motor; 0: belt drive)";
    PrescribedTemperature jacket_coolant "Chiller supply to the spindle jacket";
    Convection jacket_stator "Jacket coolant - stator sleeve";
    Convection jacket_front "Jacket coolant - front bearing seat sleeve (cap node)";

    // ---- the paper's 20 sensors (Xu et al. 2023, Table 1) ------------------------------------
    ContactSensor sensor_T1(C = 10.0, G_contact = 0.5, G_env = 0.02) "T1 spindle front: front bearing cap";
    ContactSensor sensor_T2(C = 10.0, G_contact = 0.5, G_env = 0.03) "T2 spindle front: housing flange at the bearing seat";
    ContactSensor sensor_T3(C = 12.0, G_contact = 0.15, G_env = 0.04) "T3 spindle front: labyrinth ring (poor contact)";
    ContactSensor sensor_T4(C = 10.0, G_contact = 0.4, G_env = 0.03) "T4 spindle front: housing side above the seat";
    ContactSensor sensor_T5(C = 10.0, G_contact = 0.4, G_env = 0.05) "T5 spindle front: bearing seat sleeve, inside the cavity";
    ContactSensor sensor_T6(C = 10.0, G_contact = 0.5, G_env = 0.03) "T6 headstock housing side";
    ContactSensor sensor_T7(C = 10.0, G_contact = 0.5, G_env = 0.03) "T7 drawbar cylinder base";
    ContactSensor sensor_T8(C = 10.0, G_contact = 0.5, G_env = 0.03) "T8 spindle motor housing";
    ContactSensor sensor_T9(C = 8.0, G_contact = 0.3, G_env = 0.02) "T9 headstock inner cavity (air probe near the wall)";
    ContactSensor sensor_T10(C = 10.0, G_contact = 0.3, G_env = 0.01) "T10 ambient air probe mounted on the column";
    ContactSensor sensor_T11(C = 10.0, G_contact = 0.5, G_env = 0.03) "T11 X screw bearing seat";
    ContactSensor sensor_T12(C = 10.0, G_contact = 0.5, G_env = 0.03) "T12 X nut flange";
    ContactSensor sensor_T13(C = 10.0, G_contact = 0.5, G_env = 0.03) "T13 X motor housing";
    ContactSensor sensor_T14(C = 10.0, G_contact = 0.3, G_env = 0.1) "T14 X nut bracket (between nut and table)";
    ContactSensor sensor_T15(C = 10.0, G_contact = 0.3, G_env = 0.1) "T15 X motor flange (between motor and seat)";
    ContactSensor sensor_T16(C = 10.0, G_contact = 0.5, G_env = 0.03) "T16 Y motor housing";
    ContactSensor sensor_T17(C = 10.0, G_contact = 0.3, G_env = 0.1) "T17 Y motor flange (between motor and seat)";
    ContactSensor sensor_T18(C = 10.0, G_contact = 0.5, G_env = 0.03) "T18 Y nut flange";
    ContactSensor sensor_T19(C = 10.0, G_contact = 0.3, G_env = 0.1) "T19 Y nut bracket (between nut and saddle)";
    ContactSensor sensor_T20(C = 10.0, G_contact = 0.5, G_env = 0.03) "T20 Y screw bearing seat";


    // ---- outputs ------------------------------------------------------------------------
    output Real T1_C(unit = "degC") "Sensor T1, spindle front";
    output Real T2_C(unit = "degC") "Sensor T2, spindle front";
    output Real T3_C(unit = "degC") "Sensor T3, spindle front";
    output Real T4_C(unit = "degC") "Sensor T4, spindle front";
    output Real T5_C(unit = "degC") "Sensor T5, spindle front";
    output Real T6_C(unit = "degC") "Sensor T6, headstock";
    output Real T7_C(unit = "degC") "Sensor T7, drawbar cylinder base";
    output Real T8_C(unit = "degC") "Sensor T8, spindle motor";
    output Real T9_C(unit = "degC") "Sensor T9, headstock inner cavity";
    output Real T10_C(unit = "degC") "Sensor T10, ambient";
    output Real T11_C(unit = "degC") "Sensor T11, X screw bearing seat";
    output Real T12_C(unit = "degC") "Sensor T12, X nut";
    output Real T13_C(unit = "degC") "Sensor T13, X motor";
    output Real T14_C(unit = "degC") "Sensor T14, X nut";
    output Real T15_C(unit = "degC") "Sensor T15, X motor";
    output Real T16_C(unit = "degC") "Sensor T16, Y motor";
    output Real T17_C(unit = "degC") "Sensor T17, Y motor";
    output Real T18_C(unit = "degC") "Sensor T18, Y nut";
    output Real T19_C(unit = "degC") "Sensor T19, Y nut";
    output Real T20_C(unit = "degC") "Sensor T20, Y screw bearing seat";
    output Real drift_um(unit = "um") "Axial thermal drift of the tool towards the table, relative to T_ref";
    output Real Q_front_bearing_W(unit = "W") "Front bearing friction heat";
    output Real Q_rear_bearing_W(unit = "W") "Rear bearing friction heat";
    output Real Q_spindle_motor_W(unit = "W") "Spindle motor losses";
    output Real Q_x_feed_W(unit = "W") "X drive heat (motor, nut, support bearings)";
    output Real Q_y_feed_W(unit = "W") "Y drive heat (motor, nut, support bearings)";
    output Real Q_z_feed_W(unit = "W") "Z drive heat (motor, nut, top bearings)";
    output Real Q_motor_to_column_W(unit = "W") "Heat from the spindle motor into the column";
    output Real Q_shaft_convection_W(unit = "W") "Heat from the rotating shaft into the cavity air";
    output Real Q_headstock_to_column_W(unit = "W") "Heat from the headstock into the column";
    output Real Q_cooling_W(unit = "W") "Heat removed by the spindle cooling unit";
    output Real Q_to_ambient_W(unit = "W") "Total heat released to the workshop air";
    output Real spindle_growth_um(unit = "um") "Shaft growth between front bearing and nose (towards the table)";
    output Real tool_growth_um(unit = "um") "Tool holder and test mandrel growth, nose to measured face (towards the table)";
    output Real headstock_growth_um(unit = "um") "Headstock growth between the Z nut bracket and the front bearing seat (towards the table)";
    output Real z_screw_growth_um(unit = "um") "Z ball screw growth between its top bearing and the nut (towards the table)";
    output Real column_growth_um(unit = "um") "Column growth between bed and Z screw top bearing (head away from the table)";
    output Real bed_tilt_um(unit = "um") "Bed growth under the column minus under the table (head away)";
    output Real table_growth_um(unit = "um") "Saddle and table growth (towards the tool)";
    output Real fixture_growth_um(unit = "um") "Probe fixture growth (probe towards the tool)";
    output Real front_preload_thermal_N(unit = "N") "Thermally induced preload of the front set (per bearing)";
    output Real Q_bearing_air_W(unit = "W") "Heat carried off the front bearing by the air stream through it";
    output Real Q_rotor_W(unit = "W") "Spindle motor losses released in the rotor (built-in motor)";
    output Real Q_jacket_W(unit = "W") "Heat removed by the chiller jacket";
    output Real jacket_inlet_C(unit = "degC") "Chiller jacket supply (inlet) temperature";
    output Real jacket_outlet_C(unit = "degC") "Chiller jacket return (outlet) temperature";

    // ---- five-probe drift: X, Y and the tilts A, B (ISO 230-3 / ISO 10791-10 set-up) ----------
    // Axes: +X to the operator's right, +Y from the operator towards the column, +Z up. A probe
    // reading is the mandrel's displacement relative to the probe fixture on the table, in +X or
    // +Y; the radial probes sit at two heights probe_l apart, probe 2 nearer the mandrel's end.
    parameter Real column_depth(unit = "m", min = 0.05, max = 5.0) = 0.7 "Column section front to back [EST]";
    parameter Real column_width(unit = "m", min = 0.05, max = 5.0) = 0.6 "Column section left to right [EST]";
    parameter Real housing_depth(unit = "m", min = 0.05, max = 2.0) = 0.4 "Headstock section front to back, about the spindle axis [EST]";
    parameter Real housing_width(unit = "m", min = 0.05, max = 2.0) = 0.4 "Headstock section left to right, about the spindle axis [EST]";
    parameter Real column_front_air_fraction(unit = "1", min = 0.0, max = 1.0) = 0.4 "Share of the column's air conductance on its front half (the headstock, guides and covers shield the front) [EST]";
    parameter Real housing_front_air_fraction(unit = "1", min = 0.0, max = 1.0) = 0.6 "Share of the headstock's outer air conductance on its front half (the back faces the column) [EST]";
    parameter Real column_lr_asymmetry(unit = "1", min = -0.5, max = 0.5) = 0.0 "Extra share of the headstock and motor heat entering the column's +X half (0: symmetric design)";
    parameter Real housing_lr_asymmetry(unit = "1", min = -0.5, max = 0.5) = 0.05 "Extra share of the bearing and motor-flange heat entering the headstock's +X half (belt pull and motor beside the spindle axis, lubrication inlet on one side) [EST]";
    parameter Real sun_W_per_m2(unit = "W/m2", min = 0.0, max = 1500.0) = 0.0 "Irradiance on the sunlit patch of the column's +X side wall (0: no sun)";
    parameter Real A_sun(unit = "m2", min = 0.0, max = 20.0) = 1.0 "Sunlit patch on the column's +X side wall";
    parameter Real sun_absorptivity(unit = "1", min = 0.0, max = 1.0) = 0.6 "Solar absorptivity of the painted column [VDI]";
    parameter Real z_mandrel_end(unit = "m", min = 0.0, max = 5.0) = 0.54 "Height of the mandrel's end face above the column foot (table 0.45 + fixture 0.15 - 0.06 step) [ISO230]";
    parameter Real probe_l(unit = "m", min = 0.01, max = 1.0) = 0.1 "Distance l between the two radial probe heights [ISO230]";
    parameter Real probe_end_offset(unit = "m", min = 0.0, max = 1.0) = 0.02 "Height of the lower radial probes (X2, Y2) above the mandrel's end face [ISO230]";
    parameter Real x_target_m(unit = "m", min = 0.0, max = 2.0) = 0.0 "X target: distance of the table's nut from the X screw's fixed bearing";
    parameter Real y_target_m(unit = "m", min = 0.0, max = 2.0) = 0.0 "Y target: distance of the saddle's nut from the Y screw's fixed bearing";
    HalfSection column_front(C = 736000.0, G_across = 16.0, depth = column_depth, alpha = alpha_iron)
      "Front half of the column section (towards -Y): side walls 2 x 30 mm x 1.42 m and ribs, k 48 W/(m.K), across 0.35 m [VDI, EST]";
    HalfSection column_right(C = 736000.0, G_across = 14.0, depth = column_width, alpha = alpha_iron)
      "Right half of the column section (+X): front and back walls across 0.3 m [VDI, EST]";
    HalfSection housing_front(C = 161000.0, G_across = 7.0, depth = housing_depth, alpha = alpha_iron)
      "Front half of the headstock about the spindle axis (-Y): walls 2 x 25 mm x 0.6 m across 0.2 m [VDI, EST]";
    HalfSection housing_right(C = 161000.0, G_across = 7.0, depth = housing_width, alpha = alpha_iron)
      "Right half of the headstock about the spindle axis (+X) [VDI, EST]";
    PrescribedHeatFlow sun_on_column "Absorbed sunlight on the column's +X side wall";
    Real column_mean_T(unit = "K") "Mean temperature of the column's segments";
    Real housing_mean_T(unit = "K") "Mean temperature of the headstock's segments";
    Real column_ports_Q(unit = "W") "Heat into the column through all its ports (headstock, motor, bed, Z seat, sun, probe)";
    Real housing_ports_Q(unit = "W") "Heat into the headstock through all its ports";
    Real z_carriage(unit = "m") "Height of the headstock's Z carriages above the column foot";
    Real head_hang(unit = "m") "Headstock length from the Z carriages down to the front bearing seat";
    Real seat_to_end(unit = "m") "Front bearing seat to the mandrel's end face (shaft nose part plus mandrel)";
    Real x_screw_error(unit = "m") "X screw growth between its fixed bearing and the target (table displaced in +X)";
    Real y_screw_error(unit = "m") "Y screw growth between its fixed bearing and the target (saddle displaced in +Y)";
    Real x_at_X1(unit = "m") "Mandrel displacement in +X relative to the table at probe X1";
    Real x_at_X2(unit = "m") "Mandrel displacement in +X relative to the table at probe X2";
    Real x_at_end(unit = "m") "Mandrel displacement in +X relative to the table at its end face";
    Real y_at_Y1(unit = "m") "Mandrel displacement in +Y relative to the table at probe Y1";
    Real y_at_Y2(unit = "m") "Mandrel displacement in +Y relative to the table at probe Y2";
    Real y_at_end(unit = "m") "Mandrel displacement in +Y relative to the table at its end face";
    output Real probe_X1_um(unit = "um", min = -1000.0, max = 1000.0) "Radial probe X1 (upper, nearer the spindle): mandrel displacement in +X";
    output Real probe_X2_um(unit = "um", min = -1000.0, max = 1000.0) "Radial probe X2 (lower, nearer the end face): mandrel displacement in +X";
    output Real probe_Y1_um(unit = "um", min = -1000.0, max = 1000.0) "Radial probe Y1 (upper): mandrel displacement in +Y";
    output Real probe_Y2_um(unit = "um", min = -1000.0, max = 1000.0) "Radial probe Y2 (lower): mandrel displacement in +Y";
    output Real probe_Z_um(unit = "um", min = -1000.0, max = 1000.0) "Axial probe Z on the end face: the Z drift drift_um (towards the table)";
    output Real drift_x_um(unit = "um", min = -1000.0, max = 1000.0) "X drift of the mandrel's end face relative to the table (+X), incl. the X screw at x_target_m";
    output Real drift_y_um(unit = "um", min = -1000.0, max = 1000.0) "Y drift of the mandrel's end face relative to the table (+Y), incl. the Y screw at y_target_m";
    output Real tilt_a_urad(unit = "urad", min = -10000.0, max = 10000.0) "Tilt A = (Y1 - Y2)/l: the mandrel's upper end displaced towards +Y";
    output Real tilt_b_urad(unit = "urad", min = -10000.0, max = 10000.0) "Tilt B = (X1 - X2)/l: the mandrel's upper end displaced towards +X";
  equation
    // boundaries
    ambient.T = ambient_C + 273.15;
    coolant.T = cooling_follows_ambient * (ambient_C + cooling_setpoint_C)
      + (1.0 - cooling_follows_ambient) * cooling_setpoint_C + 273.15;

    // operating inputs of the sub-assemblies
    spindle_unit.spindle_speed_rpm = spindle_speed_rpm;
    spindle_unit.Q_rotor_W = Q_rotor_W;
    headstock.spindle_speed_rpm = spindle_speed_rpm;
    test_setup.spindle_speed_rpm = spindle_speed_rpm;
    z_drive.feed_mm_per_min = feed_z_mm_per_min;
    x_drive.feed_mm_per_min = feed_x_mm_per_min;
    y_drive.feed_mm_per_min = feed_y_mm_per_min;

    // spindle unit in the headstock, tool in the spindle
    connect(spindle_unit.seat_front, headstock.seat_front);
    connect(spindle_unit.seat_rear, headstock.seat_rear);
    connect(spindle_unit.housing_top, headstock.top);
    connect(spindle_unit.cavity, headstock.cavity);
    connect(spindle_unit.taper, test_setup.taper);
    connect(spindle_unit.air, ambient.port);
    connect(headstock.air, ambient.port);
    connect(headstock.coolant, coolant.port);

    // structure
    connect(headstock.carriages, headstock_column.port_a);
    connect(headstock_column.port_b, column_unit.carriages);
    connect(headstock.column, column_unit.motor_bracket);
    connect(column_unit.air, ambient.port);
    connect(column_unit.foot, column_bed.port_a);
    connect(column_bed.port_b, bed_and_table.column_foot);
    connect(bed_and_table.air, ambient.port);
    connect(bed_and_table.floor, floor_slab.port);
    connect(floor_slab.port, floor_air.port_a);
    connect(floor_air.port_b, ambient.port);
    connect(bed_and_table.top, test_setup.table_top);
    connect(test_setup.air, ambient.port);

    // feed drives: Z on the column carries the headstock, X on the saddle moves the table, Y on the bed moves the saddle
    connect(z_drive.carriage, headstock.nut_bracket);
    connect(z_drive.base, column_unit.top);
    connect(z_drive.air, ambient.port);
    connect(x_drive.carriage, bed_and_table.x_drive);
    connect(x_drive.base, bed_and_table.x_drive);
    connect(x_drive.air, ambient.port);
    connect(y_drive.carriage, bed_and_table.saddle);
    connect(y_drive.base, bed_and_table.y_drive);
    connect(y_drive.air, ambient.port);

    // sensors
    connect(sensor_T1.port, spindle_unit.cap);
    connect(sensor_T1.port_env, ambient.port);
    connect(sensor_T2.port, headstock.seat_front);
    connect(sensor_T2.port_env, ambient.port);
    connect(sensor_T3.port, spindle_unit.cap);
    connect(sensor_T3.port_env, ambient.port);
    connect(sensor_T4.port, headstock.nut_bracket);
    connect(sensor_T4.port_env, ambient.port);
    connect(sensor_T5.port, spindle_unit.cap);
    connect(sensor_T5.port_env, headstock.cavity);
    connect(sensor_T6.port, headstock.carriages);
    connect(sensor_T6.port_env, ambient.port);
    connect(sensor_T7.port, spindle_unit.drawbar);
    connect(sensor_T7.port_env, ambient.port);
    connect(sensor_T8.port, headstock.motor);
    connect(sensor_T8.port_env, ambient.port);
    connect(sensor_T9.port, headstock.cavity);
    connect(sensor_T9.port_env, headstock.seat_rear);
    connect(sensor_T10.port, ambient.port);
    connect(sensor_T10.port_env, column_unit.wall);
    connect(sensor_T11.port, x_drive.bearing_seat);
    connect(sensor_T11.port_env, ambient.port);
    connect(sensor_T12.port, x_drive.nut);
    connect(sensor_T12.port_env, ambient.port);
    connect(sensor_T13.port, x_drive.motor);
    connect(sensor_T13.port_env, ambient.port);
    connect(sensor_T14.port, x_drive.nut);
    connect(sensor_T14.port_env, bed_and_table.x_drive);
    connect(sensor_T15.port, x_drive.motor);
    connect(sensor_T15.port_env, x_drive.bearing_seat);
    connect(sensor_T16.port, y_drive.motor);
    connect(sensor_T16.port_env, ambient.port);
    connect(sensor_T17.port, y_drive.motor);
    connect(sensor_T17.port_env, y_drive.bearing_seat);
    connect(sensor_T18.port, y_drive.nut);
    connect(sensor_T18.port_env, ambient.port);
    connect(sensor_T19.port, y_drive.nut);
    connect(sensor_T19.port_env, bed_and_table.saddle);
    connect(sensor_T20.port, y_drive.bearing_seat);
    connect(sensor_T20.port_env, ambient.port);

    // spindle-driven mechanisms and built-in motor (issue 20; every gain 0 = the earlier model)
    connect(headstock.motor, stator_housing.port_a);
    connect(stator_housing.port_b, headstock.carriages);
    // chiller jacket: supply at the room air plus an offset; heat taken at the mean coolant temperature
    jacket_coolant.T = ambient_C + jacket_offset_K + 273.15;
    jacket_stator.Gc = jacket_enabled * G_jacket_stator / (1.0 + (G_jacket_stator + G_jacket_front) / (2.0 * jacket_flow_W_per_K));
    jacket_front.Gc = jacket_enabled * G_jacket_front / (1.0 + (G_jacket_stator + G_jacket_front) / (2.0 * jacket_flow_W_per_K));
    connect(headstock.motor, jacket_stator.solid);
    connect(jacket_stator.fluid, jacket_coolant.port);
    connect(spindle_unit.cap, jacket_front.solid);
    connect(jacket_front.fluid, jacket_coolant.port);
    front_preload_thermal_N = spindle_unit.front_bearing_friction.P_thermal;
    Q_bearing_air_W = spindle_unit.bearing_air.Q_flow;
    Q_rotor_W = rotor_loss_fraction * P_spindle_motor_ref * (abs(spindle_speed_rpm) / n_ref) ^ k_spindle_motor;
    Q_jacket_W = jacket_stator.Q_flow + jacket_front.Q_flow;
    jacket_inlet_C = jacket_coolant.T - 273.15;
    jacket_outlet_C = jacket_inlet_C + Q_jacket_W / jacket_flow_W_per_K;

    // outputs
    T1_C = sensor_T1.T - 273.15;
    T2_C = sensor_T2.T - 273.15;
    T3_C = sensor_T3.T - 273.15;
    T4_C = sensor_T4.T - 273.15;
    T5_C = sensor_T5.T - 273.15;
    T6_C = sensor_T6.T - 273.15;
    T7_C = sensor_T7.T - 273.15;
    T8_C = sensor_T8.T - 273.15;
    T9_C = sensor_T9.T - 273.15;
    T10_C = sensor_T10.T - 273.15;
    T11_C = sensor_T11.T - 273.15;
    T12_C = sensor_T12.T - 273.15;
    T13_C = sensor_T13.T - 273.15;
    T14_C = sensor_T14.T - 273.15;
    T15_C = sensor_T15.T - 273.15;
    T16_C = sensor_T16.T - 273.15;
    T17_C = sensor_T17.T - 273.15;
    T18_C = sensor_T18.T - 273.15;
    T19_C = sensor_T19.T - 273.15;
    T20_C = sensor_T20.T - 273.15;
    spindle_growth_um = 1.0e6 * spindle_unit.spindle_shaft.dL;
    tool_growth_um = 1.0e6 * test_setup.tool.dL;
    headstock_growth_um = 1.0e6 * headstock.housing.dL;
    z_screw_growth_um = 1.0e6 * z_drive.z_screw.dL;
    column_growth_um = 1.0e6 * column_unit.column.dL;
    bed_tilt_um = 1.0e6 * alpha_iron * H_bed * (bed_and_table.bed.port_b.T - bed_and_table.bed.port_1.T);
    table_growth_um = 1.0e6 * bed_and_table.table.dL;
    fixture_growth_um = 1.0e6 * test_setup.fixture.dL;
    drift_um = spindle_growth_um + tool_growth_um + headstock_growth_um + z_screw_growth_um - column_growth_um
      - bed_tilt_um + table_growth_um + fixture_growth_um;
    Q_front_bearing_W = spindle_unit.front_bearing_friction.Q_flow;
    Q_rear_bearing_W = spindle_unit.rear_bearing_friction.Q_flow;
    Q_spindle_motor_W = headstock.spindle_motor_loss.Q_flow + Q_rotor_W;
    Q_x_feed_W = x_drive.x_nut_friction.Q_flow + x_drive.x_bearing_friction.Q_flow + x_drive.x_motor_loss.Q_flow;
    Q_y_feed_W = y_drive.y_nut_friction.Q_flow + y_drive.y_bearing_friction.Q_flow + y_drive.y_motor_loss.Q_flow;
    Q_z_feed_W = z_drive.z_nut_friction.Q_flow + z_drive.z_bearing_friction.Q_flow + z_drive.z_motor_loss.Q_flow;
    Q_motor_to_column_W = headstock.motor_column.Q_flow;
    Q_shaft_convection_W = -spindle_unit.spindle_shaft.side_1.Q_flow;
    Q_headstock_to_column_W = headstock_column.Q_flow;
    Q_cooling_W = coolant.port.Q_flow;
    Q_to_ambient_W = ambient.port.Q_flow;

    // five-probe drift: the halves' heat (their share of the part's port heat, the sources on
    // their side, their own air exchange), then the bending and the screws at the targets
    column_mean_T = sum(column_unit.column.T) / nSeg;
    housing_mean_T = sum(headstock.housing.T) / nSeg;
    column_ports_Q = column_unit.column.port_a.Q_flow + column_unit.column.port_b.Q_flow + column_unit.column.port_1.Q_flow + column_unit.column.port_2.Q_flow + column_unit.column.port_3.Q_flow;
    housing_ports_Q = headstock.housing.port_a.Q_flow + headstock.housing.port_b.Q_flow + headstock.housing.port_1.Q_flow + headstock.housing.port_2.Q_flow + headstock.housing.port_3.Q_flow;
    sun_on_column.Q_flow = sun_absorptivity * A_sun * sun_W_per_m2;
    connect(sun_on_column.port, column_unit.wall);
    column_front.T_mean = column_mean_T;
    column_front.Q_in = 0.5 * column_ports_Q + 0.5 * (headstock_column.Q_flow + headstock.motor_column.Q_flow)
      - column_front_air_fraction * column_unit.column.G_side1 * (column_front.T - ambient.T);
    column_right.T_mean = column_mean_T;
    column_right.Q_in = 0.5 * column_ports_Q + column_lr_asymmetry * (headstock_column.Q_flow + headstock.motor_column.Q_flow)
      + 0.5 * sun_on_column.Q_flow - 0.5 * column_unit.column.G_side1 * (column_right.T - ambient.T);
    housing_front.T_mean = housing_mean_T;
    housing_front.Q_in = 0.5 * housing_ports_Q + 0.5 * headstock_column.Q_flow
      - housing_front_air_fraction * headstock.housing.G_side1 * (housing_front.T - ambient.T)
      - 0.5 * headstock.housing.G_side2 * (housing_front.T - headstock.inner_cavity.T);
    housing_right.T_mean = housing_mean_T;
    housing_right.Q_in = 0.5 * housing_ports_Q + housing_lr_asymmetry * (spindle_unit.fb_housing.Q_flow + spindle_unit.cap_housing.Q_flow + spindle_unit.rb_housing.Q_flow + headstock.motor_housing.Q_flow)
      - 0.5 * headstock.housing.G_side1 * (housing_right.T - ambient.T) - 0.5 * headstock.housing.G_side2 * (housing_right.T - headstock.inner_cavity.T);
    z_carriage = column_unit.column.x1 * column_unit.column.L;
    head_hang = headstock.housing.x1 * headstock.housing.L;
    seat_to_end = spindle_unit.spindle_shaft.x1 * spindle_unit.spindle_shaft.L + test_setup.tool.L;
    x_screw_error = alpha_steel * (x_drive.x_screw.T - T_ref) * x_target_m;
    y_screw_error = alpha_steel * (y_drive.y_screw.T - T_ref) * y_target_m;
    // column (cantilever from the bed): the head at height z moves by kappa z_c (z - z_c/2)
    // towards the cooler side; headstock (hanging from the carriages, length h): a point d
    // below its seat moves by kappa h (h/2 + d) towards the cooler side; the tool relative to
    // the table moves against the screw's growth
    x_at_X1 = -column_right.curvature * z_carriage * (z_mandrel_end + probe_end_offset + probe_l - z_carriage / 2.0)
      - housing_right.curvature * head_hang * (head_hang / 2.0 + seat_to_end - probe_end_offset - probe_l) - x_screw_error;
    x_at_X2 = -column_right.curvature * z_carriage * (z_mandrel_end + probe_end_offset - z_carriage / 2.0)
      - housing_right.curvature * head_hang * (head_hang / 2.0 + seat_to_end - probe_end_offset) - x_screw_error;
    x_at_end = -column_right.curvature * z_carriage * (z_mandrel_end - z_carriage / 2.0)
      - housing_right.curvature * head_hang * (head_hang / 2.0 + seat_to_end) - x_screw_error;
    y_at_Y1 = column_front.curvature * z_carriage * (z_mandrel_end + probe_end_offset + probe_l - z_carriage / 2.0)
      + housing_front.curvature * head_hang * (head_hang / 2.0 + seat_to_end - probe_end_offset - probe_l) - y_screw_error;
    y_at_Y2 = column_front.curvature * z_carriage * (z_mandrel_end + probe_end_offset - z_carriage / 2.0)
      + housing_front.curvature * head_hang * (head_hang / 2.0 + seat_to_end - probe_end_offset) - y_screw_error;
    y_at_end = column_front.curvature * z_carriage * (z_mandrel_end - z_carriage / 2.0)
      + housing_front.curvature * head_hang * (head_hang / 2.0 + seat_to_end) - y_screw_error;
    probe_X1_um = 1.0e6 * x_at_X1;
    probe_X2_um = 1.0e6 * x_at_X2;
    probe_Y1_um = 1.0e6 * y_at_Y1;
    probe_Y2_um = 1.0e6 * y_at_Y2;
    probe_Z_um = drift_um;
    drift_x_um = 1.0e6 * x_at_end;
    drift_y_um = 1.0e6 * y_at_end;
    tilt_a_urad = (probe_Y1_um - probe_Y2_um) / probe_l;
    tilt_b_urad = (probe_X1_um - probe_X2_um) / probe_l;
  end MachiningCentre;

  package Examples "Small models, each exercising a few components against a reference result and, where one exists, an analytical solution"
    // Each has an experiment annotation; its reference result is
    // models/Resources/Reference/SpindleBench/Examples/<name>.csv, written by
    //   python -m spindlebench.model.examples --write-references
    // and compared by tests/model/test_model_examples.py (through the build's pymoca/CasADi path).

    model TwoSegmentRod "A rod of two segments between a warm and a cool end: the steady state is the linear profile"
      import SpindleBench.HeatTransfer.Components.SegmentedSolid;
      import SpindleBench.HeatTransfer.Sources.PrescribedTemperature;
      import SpindleBench.HeatTransfer.Sources.PrescribedHeatFlow;
      parameter Real T_warm(unit = "K", min = 250.0, max = 400.0) = 313.15 "Temperature held at end a (x = 0)";
      parameter Real T_cool(unit = "K", min = 250.0, max = 400.0) = 293.15 "Temperature held at end b (x = 1)";
      SegmentedSolid rod(n = 2, C = 2000.0, G = 5.0, L = 0.5, alpha = 1.15e-5, T_nominal = 293.15)
        "Steel rod, 0.5 m, 2 segments starting at 20 degC; end-to-end conductance 5 W/K";
      PrescribedTemperature warm "Warm end";
      PrescribedTemperature cool "Cool end";
      PrescribedHeatFlow no_heat_1 "Nothing enters through positional port 1";
      PrescribedHeatFlow no_heat_2 "Nothing enters through positional port 2";
      PrescribedHeatFlow no_heat_3 "Nothing enters through positional port 3";
      output Real T1_C(unit = "degC") "Segment 1 (centre at x = 1/4)";
      output Real T2_C(unit = "degC") "Segment 2 (centre at x = 3/4)";
      output Real Q_W(unit = "W") "Heat entering the rod at the warm end";
      output Real dL_um(unit = "um") "Elongation of the rod relative to 20 degC";
    equation
      warm.T = T_warm;
      cool.T = T_cool;
      no_heat_1.Q_flow = 0.0;
      no_heat_2.Q_flow = 0.0;
      no_heat_3.Q_flow = 0.0;
      rod.G_side1 = 0.0;
      rod.G_side2 = 0.0;
      connect(warm.port, rod.port_a);
      connect(rod.port_b, cool.port);
      connect(no_heat_1.port, rod.port_1);
      connect(no_heat_2.port, rod.port_2);
      connect(no_heat_3.port, rod.port_3);
      connect(rod.side_1, cool.port);
      connect(rod.side_2, cool.port);
      T1_C = rod.T[1] - 273.15;
      T2_C = rod.T[2] - 273.15;
      Q_W = rod.port_a.Q_flow;
      dL_um = 1.0e6 * rod.dL;
      annotation(experiment(StartTime = 0.0, StopTime = 600.0, Interval = 10.0, Tolerance = 1.0e-8));
    end TwoSegmentRod;

    model BearingAtSpeed "The front bearing set at 8000 rpm in a seat held at 20 degC: Palmgren friction heat against the seat conductance"
      import SpindleBench.HeatTransfer.Components.HeatCapacitor;
      import SpindleBench.HeatTransfer.Components.ThermalConductor;
      import SpindleBench.HeatTransfer.Sources.PrescribedTemperature;
      import SpindleBench.Machine.BearingFriction;
      parameter Real n_rpm(unit = "rev/min", min = 0.0, max = 30000.0) = 8000.0 "Shaft speed";
      parameter Real T_seat(unit = "K", min = 250.0, max = 400.0) = 293.15 "Temperature held at the seat";
      BearingFriction friction(f0 = 0.75, z = 2.0, f1 = 4.0e-4, P1 = 1500.0, dm = 0.09, nu_40 = 22.0, nu_100 = 4.3)
        "The machine's front set: 2 x 7014, ISO VG 22 base oil [SKF, HK, D341]";
      HeatCapacitor rings(C = 1000.0) "Bearing rings and balls (2.2 kg)";
      ThermalConductor seat(G = 15.0) "Outer rings - seat [BT, HOL]";
      PrescribedTemperature housing "The seat, held at T_seat";
      output Real T_rings_C(unit = "degC") "Bearing ring temperature";
      output Real Q_friction_W(unit = "W") "Friction heat of the set";
      output Real Q_seat_W(unit = "W") "Heat conducted into the seat";
    equation
      friction.n_rpm = n_rpm;
      friction.P_thermal = 0.0;
      housing.T = T_seat;
      connect(friction.port, rings.port);
      connect(rings.port, seat.port_a);
      connect(seat.port_b, housing.port);
      T_rings_C = rings.T - 273.15;
      Q_friction_W = friction.Q_flow;
      Q_seat_W = seat.Q_flow;
      annotation(experiment(StartTime = 0.0, StopTime = 900.0, Interval = 10.0, Tolerance = 1.0e-8));
    end BearingAtSpeed;

    model ProbeOnPlate "A contact probe put on a plate at 40 degC in 20 degC air: a first-order lag towards a reading between the two"
      import SpindleBench.HeatTransfer.Sources.PrescribedTemperature;
      import SpindleBench.Machine.ContactSensor;
      parameter Real T_plate(unit = "K", min = 250.0, max = 400.0) = 313.15 "Plate temperature";
      parameter Real T_air(unit = "K", min = 250.0, max = 400.0) = 293.15 "Air temperature";
      ContactSensor probe(C = 10.0, G_contact = 0.5, G_env = 0.02) "The machine's T1 probe, starting at 20 degC";
      PrescribedTemperature plate "The plate";
      PrescribedTemperature air "The air";
      output Real T_probe_C(unit = "degC") "Probe reading";
    equation
      plate.T = T_plate;
      air.T = T_air;
      connect(probe.port, plate.port);
      connect(probe.port_env, air.port);
      T_probe_C = probe.T - 273.15;
      annotation(experiment(StartTime = 0.0, StopTime = 120.0, Interval = 1.0, Tolerance = 1.0e-8));
    end ProbeOnPlate;

  end Examples;

end SpindleBench;

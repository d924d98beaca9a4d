; The cable tracking mission of the seed as a planning problem (8.5.1.2):
; the planning operators of Table 8.1, the facts of Table 8.2. Each action's
; :mcl names the MCL mission operator it runs, defined in cable.mcl.
;
; Differences from Table 8.1, all justified in docs/planning.md:
; - AchieveAltitudeOp is missing from the table although the text lists it
;   among the seven operators and the initial plan uses it: written here.
; - GotoOp also needs `surface`: its mission GotoMCLop( b.x, b.y ) only takes
;   a position on the plane, and the vehicle cannot travel more than 50 m
;   without a GPS fix (8.5.2), so transits are made on the surface.
; - CableTrackingOp also needs `seafloor`: it keeps an altitude over the
;   seabed (CableTrackingMCLop( altitude, params_NAC )); and `in inspection`,
;   where the cable lies (else a re-plan may track it from another zone).
; - CheckAlarmOp also adds `surface` (and deletes `seafloor`): its mission
;   CheckAlarmMCLop surfaces before checking the vehicle.
; - Table 8.1's type "Object" is `target` (`object` is PDDL's root type);
;   "seabottom" (Table 8.2) is `seafloor` (Table 8.1); "alarms" / "no_alarm"
;   are `alarm` / `no_alarms`.
; Costs are the expected durations in seconds (transits at 1 m/s).
(define (domain cable-tracking)
  (:requirements :strips :typing :equality :action-costs)
  (:types robot zone target)
  (:constants inspection - zone)
  (:predicates
    (position_bad ?r - robot) (position_ok ?r - robot)
    (surface ?r - robot) (seafloor ?r - robot)
    (no_alarms ?r - robot) (alarm ?r - robot)
    (in ?r - robot ?z - zone)
    (not_found ?o - target) (found ?o - target)
    (not_mapped ?o - target) (mapped ?o - target))
  (:functions
    (x ?z - zone) (y ?z - zone) (distance ?a ?b - zone)
    (altitude ?r - robot) (dive_timeout ?r - robot) (search_timeout ?r - robot)
    (description ?o - target) (params_nac ?o - target)
    (total-cost) - number)

  (:action TakeFixOp
    :parameters (?r - robot)
    :precondition (and (surface ?r) (position_bad ?r) (no_alarms ?r))
    :effect (and (position_ok ?r) (not (position_bad ?r)) (increase (total-cost) 30))
    :mcl (TakeFixMCLop))

  (:action SearchCableOp
    :parameters (?r - robot ?o - target)
    :precondition (and (seafloor ?r) (position_ok ?r) (no_alarms ?r) (in ?r inspection) (not_found ?o))
    :effect (and (found ?o) (not (not_found ?o)) (increase (total-cost) 120))
    :mcl (SearchCableMCLop ?r.search_timeout ?o.description ?r.altitude))

  (:action CableTrackingOp
    :parameters (?r - robot ?o - target)
    :precondition (and (seafloor ?r) (position_ok ?r) (no_alarms ?r) (in ?r inspection) (found ?o) (not_mapped ?o))
    :effect (and (mapped ?o) (not (not_mapped ?o)) (increase (total-cost) 300))
    :mcl (CableTrackingMCLop ?r.altitude ?o.params_nac))

  (:action GotoOp
    :parameters (?r - robot ?a ?b - zone)
    :precondition (and (in ?r ?a) (surface ?r) (position_ok ?r) (no_alarms ?r) (not (= ?a ?b)))
    :effect (and (in ?r ?b) (not (in ?r ?a)) (increase (total-cost) (distance ?a ?b)))
    :mcl (GotoMCLop ?b.x ?b.y))

  (:action SurfaceOp
    :parameters (?r - robot)
    :precondition (seafloor ?r)
    :effect (and (surface ?r) (not (seafloor ?r)) (increase (total-cost) 20))
    :mcl (SurfaceMCLop))

  (:action AchieveAltitudeOp
    :parameters (?r - robot)
    :precondition (and (surface ?r) (position_ok ?r) (no_alarms ?r))
    :effect (and (seafloor ?r) (not (surface ?r)) (increase (total-cost) 20))
    :mcl (AchieveAltitudeMCLop ?r.altitude ?r.dive_timeout))

  (:action CheckAlarmOp
    :parameters (?r - robot)
    :precondition (alarm ?r)
    :effect (and (no_alarms ?r) (not (alarm ?r)) (surface ?r) (not (seafloor ?r)) (increase (total-cost) 60))
    :mcl (CheckAlarmMCLop)))

; Extracts 7.1 and 7.2 in plain STRIPS PDDL with typing: the planning
; operator `move`, with its expression l1 != l2. A second expression
; compares attributes: the vehicle only goes to locations no deeper than its
; maximum depth. The MCL mission each action runs comes from the `pddl_map`
; of operators.mcl (`mcl plan examples/planning/move/operators.mcl`);
; move.mcl writes the same problem in MCL.
(define (domain move)
  (:requirements :strips :typing :equality)
  (:types vehicle location)
  (:predicates (in ?v - vehicle ?l - location))
  (:functions (x ?l - location) (y ?l - location) (z ?l - location)
              (max_depth ?v - vehicle))
  (:action move
    :parameters (?v - vehicle ?l1 - location ?l2 - location)
    :precondition (and (in ?v ?l1) (not (= ?l1 ?l2)) (<= ?l2.z (max_depth ?v)))
    :effect (and (in ?v ?l2) (not (in ?v ?l1)))))

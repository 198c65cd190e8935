;;;; tools/snapshot-one.lisp -- one process of make count-snapshots (physics.org, #SNCOST): load the
;;;; engine of the tree ROOT, run the 3000-ball basin 240 steps (4 s) under the widest family,
;;;; snapshot it and restore the snapshot into a second basin, then run ROUNDS rounds of WHAT
;;;; (snapshot: a snapshot of the first world and its restore into the second; step: a step of the
;;;; first; none: nothing) and print
;;;;   snapshot WHAT ROUNDS HASH
;;;; with the first world's state hash.  Its start, tools/one-process.lisp, is tools/against-one.lisp's.
;;;;
;;;; Usage: sbcl --script tools/snapshot-one.lisp ROOT/ WHAT ROUNDS

(load (merge-pathnames "one-process.lisp" *load-truename*))

(defvar *snapshot-arguments* (one-process-arguments "snapshot-one" "ROOT/ WHAT ROUNDS" 3))

(destructuring-bind (root what rounds) *snapshot-arguments*
  (declare (ignore root))
  (flet ((call (name &rest arguments) (apply (find-symbol name :luv-physics) arguments)))
    (let* ((world (call "MAKE-BASIN-WORLD" 3000 :kernels :auto))
           (other (call "MAKE-BASIN-WORLD" 3000 :kernels :auto))
           (n (parse-integer rounds))
           (buffer nil))
      (dotimes (i 240) (call "STEP-PHYSICS-WORLD" world))
      ;; the buffer and both worlds' scratch made before the rounds, as a rollback loop has them
      (setf buffer (call "SNAPSHOT-PHYSICS-WORLD" world))
      (call "RESTORE-PHYSICS-WORLD" other buffer)
      (dotimes (i n)
        (cond ((string= what "snapshot")
               (call "SNAPSHOT-PHYSICS-WORLD" world buffer)
               (call "RESTORE-PHYSICS-WORLD" other buffer))
              ((string= what "step") (call "STEP-PHYSICS-WORLD" world))))
      (format t "~&snapshot ~A ~D ~D~%" what n (call "PHYSICS-WORLD-STATE-HASH" world))
      (finish-output))))
